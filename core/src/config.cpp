#include "gsf/config.h"

#include "gsf/parameters.h"

namespace gsf {

// The ranges and rules are the parameter list's (parameters.def, check_config in parameters.cpp).
Status validate(const LocalizerConfig& c) { return check_config(c).status; }

const ClassTable& label_set(const LocalizerConfig& c) {
  if (c.classes) return *c.classes;
  // Built once on first use (static storage, no heap); read-only afterwards.
  static const ClassTable kitti = [] {
    ClassTable t;
    semantic_kitti_class_table(&t);
    return t;
  }();
  return kitti;
}

ClassMask instance_label_mask(const LocalizerConfig& c) {
  if (!c.classes) return c.cluster.instance_classes;
  // Only classes some raw id maps to can label an instance (unlisted classes keep their default role).
  ClassMask m = c.classes->instance_classes() & c.classes->mapped_classes();
  if (c.classes->pole_host_classes()) m |= class_bit(kPole);
  if (c.classes->trunk_host_classes()) m |= class_bit(kTrunk);
  return m;
}

PoleConfig effective_pole_config(const LocalizerConfig& c) {
  PoleConfig p = c.poles;
  p.set_hosts(label_set(c));
  return p;
}

MapParams map_params_from(const LocalizerConfig& c) {
  MapParams p{};
  p.num_classes = kNumClasses;
  p.instance_class_mask = instance_label_mask(c);
  p.class_table_id = label_set(c).id();
  p.field_input_dims = c.field.input_dims;
  p.inducing_stride = c.field.inducing_points;
  p.grid_nx = c.field.grid_nx;
  p.grid_ny = c.field.grid_ny;
  p.grid_layers = c.field.grid_layers;
  p.triangle_neighbours = c.triangle.map_k();
  p.grid_spacing = c.field.grid_spacing;
  p.layer_spacing = c.field.layer_spacing;
  p.grid_z0 = c.field.grid_z0;
  p.length_scale = c.field.length_scale;
  p.signal_variance = c.field.signal_variance;
  p.noise_variance = c.field.noise_variance;
  p.field_radius = c.field.radius;
  p.voxel_size = c.voxel.voxel_size;
  p.side_bin = c.triangle.side_bin;
  p.min_side = c.triangle.min_side;
  p.max_side = c.triangle.max_side;
  return p;
}

Status check_map_params(const LocalizerConfig& c, const MapParams& p) {
  const MapParams w = map_params_from(c);
  // Everything that shapes a field, a probe grid or a triangle key must match exactly.
  if (p.num_classes != w.num_classes || p.instance_class_mask != w.instance_class_mask ||
      p.field_input_dims != w.field_input_dims || p.inducing_stride != w.inducing_stride || p.grid_nx != w.grid_nx ||
      p.grid_ny != w.grid_ny || p.grid_layers != w.grid_layers || p.grid_spacing != w.grid_spacing ||
      p.layer_spacing != w.layer_spacing || p.grid_z0 != w.grid_z0 || p.length_scale != w.length_scale ||
      p.signal_variance != w.signal_variance || p.noise_variance != w.noise_variance ||
      p.field_radius != w.field_radius || p.voxel_size != w.voxel_size || p.side_bin != w.side_bin ||
      p.triangle_neighbours != w.triangle_neighbours || p.min_side != w.min_side || p.max_side != w.max_side ||
      p.class_table_id != w.class_table_id)
    return Status::ConfigMismatch;
  return Status::Ok;
}

}  // namespace gsf
