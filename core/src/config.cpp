#include "gsf/config.h"

#include <cmath>

namespace gsf {

Status validate(const LocalizerConfig& c) {
  if (c.max_scan_points == 0) return Status::InvalidArgument;
  Status s = validate(c.field);
  if (s != Status::Ok) return s;
  s = validate(c.triangle);
  if (s != Status::Ok) return s;
  const MatchConfig& m = c.match;
  if (m.max_matches_per_triangle == 0 || m.max_matches_per_triangle > (1u << 20) || !(m.min_similarity >= 0) ||
      !(m.vertex_tie_tolerance >= 0 && m.vertex_tie_tolerance < 1) || m.max_candidates < 3 ||
      m.max_candidates > (1u << 22) || m.max_correspondences < 3 || m.max_correspondences > 4096 ||
      m.max_field_points == 0 || m.heading_sample_triangles == 0 || m.max_matches_per_scan == 0)
    return Status::InvalidArgument;
  const GsfFilterConfig& g = c.gsf;
  if (g.yaw_bins < 4 || g.yaw_bins > 4096 || g.probe_cache_slots == 0 || g.similarity_cache_slots == 0 ||
      !(g.tau > 0) || !(g.observed_variance > 0) || !(g.covariance_weight >= 0))
    return Status::InvalidArgument;
  const HypothesisConfig& h = c.hypotheses;
  if (h.max_hypotheses == 0 || h.max_hypotheses > PoseHypotheses::kMaxHypotheses || h.first_budget == 0 ||
      h.next_budget == 0 || !(h.consistency_eps > 0) || !(h.tls_threshold > 0) || h.min_inliers < 3 ||
      h.max_iterations == 0 || !(h.same_pose_m >= 0) || !(h.same_pose_deg >= 0) ||
      !(h.heading_separation_deg > 0.0f && h.heading_separation_deg < 90.0f) || h.max_peeled == 0 ||
      !(h.shift_bin > 0) || !(h.max_tilt_deg >= 0 && h.max_tilt_deg <= 180) || h.tls_threshold > h.shift_bin ||
      h.shift_vote_pairs > (1u << 20))
    return Status::InvalidArgument;
  if (c.verify.max_points == 0 || c.verify.refine_top > 64 || c.verify.coarse_divisor == 0 ||
      c.verify.search_divisor == 0 || c.verify.polish_divisor == 0 || c.verify.full_top == 0 ||
      !(c.verify.refine_step_m >= 0) || !(c.verify.refine_step_deg >= 0) || c.verify.refine_rounds > 16 ||
      !(c.verify.rarity_exponent >= 0 && c.verify.rarity_exponent <= 2) ||
      !(c.verify.disagree_weight >= 0 && c.verify.disagree_weight <= 100))
    return Status::InvalidArgument;
  if (!(c.confidence.min_probability >= 0.0f && c.confidence.min_probability <= 1.0f)) return Status::InvalidArgument;
  if (c.cluster.max_instances == 0 || c.cluster.max_instances >= (1u << 16)) return Status::InvalidArgument;
  return Status::Ok;
}

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
