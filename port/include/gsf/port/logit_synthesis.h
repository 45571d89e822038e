// Synthetic per-point logits for datasets without a segmentation network's output.
//
// Confusion model (documented in docs/data-formats.md): a point of dense class c is "predicted" as a
// partner class with probability scale * p_c (partners: vegetation<->terrain, pole<->trunk<->
// traffic-sign, car->truck/other-vehicle, road<->parking, sidewalk->terrain/parking, building<->fence),
// otherwise as c. Logits: N(0, noise_sigma) on every class, +margin on the predicted class and
// +margin/2 on the true class when they differ (the network's runner-up). Ignored/unknown labels get
// flat noise only. Each point draws from its own stream seeded by (seed, scan_id, index), so results do
// not depend on call order or chunking.
#pragma once
#include <cstdint>

#include "gsf/class_table.h"

namespace gsf::port {

struct LogitModel {
  uint64_t seed = 1;
  float confusion_scale = 1.0f;  // multiplies every confusion probability
  float noise_sigma = 0.5f;
  float margin = 4.0f;
};

// Probability that dense class c is predicted as something else (before confusion_scale).
float confusion_probability(int dense_class);
// Number of partner classes of c, and the k-th one.
int confusion_partner_count(int dense_class);
int confusion_partner(int dense_class, int k);

// `labels` are raw ids of `classes` (nullptr: SemanticKITTI ids). The relabelled ids are raw ids of the
// same label set: the predicted library class's lowest raw id (the label is kept when no raw id maps
// to the predicted class, or for ignored and unknown labels); high 16 bits (instance ids) are kept.
void synthesize_logits(const LogitModel& model, uint64_t scan_id, const uint32_t* labels, uint32_t count,
                       float* out_logits, uint32_t* relabel_out_or_null, const ClassTable* classes = nullptr);

}  // namespace gsf::port
