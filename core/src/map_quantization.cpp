#include "gsf/detail/map_quantization.h"

namespace gsf {

void quantize_instance_grid(const float* mean, const float* var, uint64_t g, uint64_t d, MapInstance* in,
                            uint8_t* q_mean, uint16_t* q_var) {
  quantization_scale(mean, g * d, kGridMeanLevels, &in->mean_min, &in->mean_step);
  quantization_scale(var, g, kGridVarLevels, &in->var_min, &in->var_step);
  for (uint64_t k = 0; k < g * d; ++k)
    q_mean[k] = static_cast<uint8_t>(quantize_level(mean[k], in->mean_min, in->mean_step, kGridMeanLevels));
  for (uint64_t k = 0; k < g; ++k)
    q_var[k] = static_cast<uint16_t>(quantize_level(var[k], in->var_min, in->var_step, kGridVarLevels));
}

void dequantize_instance_grid(const MapView& view, uint32_t i, float* mean, float* var, const uint8_t* only) {
  const MapInstance& in = view.instances[i];
  const uint64_t g = view.grid_points(), d = view.params.num_classes, gd = g * d;
  const uint8_t* qm = view.grid_mean + i * gd;
  const uint16_t* qv = view.grid_var + i * g;
  if (only == nullptr) {
    for (uint64_t k = 0; k < gd; ++k) mean[k] = dequantize_level(qm[k], in.mean_min, in.mean_step);
  } else {
    for (uint64_t s = 0; s < g; ++s)
      if (only[s])
        for (uint64_t k = s * d; k < (s + 1) * d; ++k) mean[k] = dequantize_level(qm[k], in.mean_min, in.mean_step);
  }
  for (uint64_t k = 0; k < g; ++k) var[k] = dequantize_level(qv[k], in.var_min, in.var_step);
}

}  // namespace gsf
