// Simulated segmentation-network errors on ground-truth labels (issue 24): what a real network's
// predicted labels look like, so that clean labels - simulated or real - can be evaluated as if a
// network had written them. Used by the simulator (`gsf simulate`, on its SemanticKITTI labels as it
// writes them) and by `gsf build-map / evaluate / localize` (on real labels as each scan is read).
//
// A host-side evaluation instrument, not part of what firmware links: it lives in tools/ as its own small
// library (gsf_label_errors, depending on libgsf's PRNG only) so that tools/sim and tools/gsf both use
// it without one depending on the other; the component search allocates.
//
// Three families, in the order the simulator (and apply_label_errors) applies them:
//   object confusion - whole objects relabelled to one partner class (a network calls a whole pole a
//                      trunk, not a point here and there);
//   thin misses      - pole / sign / trunk points lost with range (SemanticKITTI ids only);
//   label noise      - single points relabelled to a partner class.
// Each family draws from its own stream of the scan's seed; same seed and labels -> the same output.
// docs/simulator.md has the partner tables and the rules.
#pragma once
#include <cstdint>
#include <string>

namespace gsf::label_errors {

// The ids the labels are in: SemanticKITTI words (semantic id in the low 16 bits, instance id in the high
// 16), or raw nuScenes-lidarseg classes 0..31 (no instance ids).
enum class LabelSpace : uint8_t { SemanticKitti, NuScenesLidarseg };
const char* label_space_name(LabelSpace space);  // "semantic-kitti", "nuscenes-lidarseg"

// The plausible confusion partners of a class: 0..2 of them, the first the likelier (3 confusions in 4
// when there are two); 0 for classes nothing is confused with (unlabeled, noise, ego, moving-*).
int label_partner_count(uint16_t semantic, LabelSpace space = LabelSpace::SemanticKitti);
uint16_t label_partner(uint16_t semantic, int k, LabelSpace space = LabelSpace::SemanticKitti);

// Replaces the class of a share `p` of points by a partner (instance bits kept); one draw per point.
void apply_label_noise(uint32_t* labels, uint32_t count, float p, uint64_t seed,
                       LabelSpace space = LabelSpace::SemanticKitti);

// Whole-object confusion by instance id (SemanticKITTI words): each instance (id != 0) with partner classes
// is, with probability p, relabelled whole to one partner; instance bits kept. The draw is a function of
// (seed, instance id) alone: every point of the instance agrees, whatever their order.
void apply_object_confusion(uint32_t* labels, uint32_t count, float p, uint64_t seed);

// Whole-object confusion for objects without instance ids: the points of the space's object classes
// (object_component_class) with instance id 0 are grouped per class into components of a kObjectCell grid,
// 26-connected; each component is, with probability p, relabelled whole to one partner. The draw is a
// function of (seed, class, the component's smallest cell): the same whatever the point order.
// SemanticKITTI: car, trunk, pole, traffic-sign (the library's instance classes; real SemanticKITTI
// gives poles, signs and trunks no instance id). nuScenes-lidarseg: the thing classes 2..23 (humans,
// movable objects, bicycle racks, vehicles) and thin components of static.manmade / static.vegetation
// (xy extent <= kThinObjectExtent: poles, posts, trunks, what the library extracts as geometric poles).
constexpr float kObjectCell = 0.5f;        // m
constexpr float kThinObjectExtent = 1.5f;  // m, per horizontal axis
bool object_component_class(uint16_t semantic, LabelSpace space);
void apply_component_confusion(const float* xyzi, uint32_t* labels, uint32_t count, float p, uint64_t seed,
                               LabelSpace space);

// Range-dependent misses of thin classes (SemanticKITTI ids): a pole (80), traffic-sign (81) or trunk (71)
// point at horizontal range r from the sensor (its x, y in the sensor frame) loses its class with
// probability thin_miss_probability(p, r): a pole or sign point becomes building (50), a trunk point
// vegetation (70), what a network says of a thin thing against its background; its instance bits are
// cleared. One draw per point, whatever its class.
constexpr float kThinMissNear = 10.0f, kThinMissFar = 60.0f;  // m: never missed below, at rate p beyond
float thin_miss_probability(float p, float range);            // p * clamp((r - near) / (far - near), 0, 1)
void apply_thin_miss(const float* xyzi, uint32_t* labels, uint32_t count, float p, uint64_t seed);

// Spurious thin objects: what an unstable segmentation of real scans shows (a patch of wall or hedge
// read as a pole or a trunk in one scan and not in the next, so a scan holds instances no map has; real
// nuScenes drives explain 45% of their instances at the true pose, simulated ones 80%). Per scan,
// round(p x the scan's instance count) (stochastic rounding) points of building (50) or vegetation (70)
// between kSpuriousNear and kSpuriousFar horizontal range are drawn, and every building or vegetation
// point within kSpuriousRadius of each (horizontally) becomes pole (80) or trunk (71), with an instance
// id of its own (kSpuriousInstanceBase + k). Needs instance ids in `labels` to count the instances.
constexpr float kSpuriousNear = 5.0f, kSpuriousFar = 40.0f, kSpuriousRadius = 0.3f;  // m
constexpr uint32_t kSpuriousInstanceBase = 0xF000u;
void apply_spurious_objects(const float* xyzi, uint32_t* labels, uint32_t count, float p, uint64_t seed);

// The rates of the three families (each 0..1).
struct LabelErrorRates {
  float label_noise = 0.0f;
  float object_confusion = 0.0f;
  float thin_miss = 0.0f;
  bool any() const { return label_noise > 0 || object_confusion > 0 || thin_miss > 0; }
};

// Salts of the families' streams (the simulator's since issue 24: its outputs stay byte-identical).
constexpr uint64_t kObjectSalt = 0x4F424A434F4E4655ULL, kThinSalt = 0x5448494E4D495353ULL,
                   kNoiseSalt = 0x4C4142454C4E4F49ULL, kComponentSalt = 0x434F4D504F4E454EULL,
                   kSpuriousSalt = 0x53505552494F5553ULL;

// One scan of real labels as a network would have written them: object confusion (instance ids, then
// components), thin misses, label noise. nuScenes-lidarseg has no thin-miss effect: its labels have no
// pole, sign or trunk class, and a missed one takes its background's class, static.manmade /
// static.vegetation, which it already has.
void apply_label_errors(const LabelErrorRates& rates, LabelSpace space, const float* xyzi, uint32_t* labels,
                        uint32_t count, uint64_t scan_seed);

// The seed of a real scan's errors: from the run's noise seed, the sequence's name and the file's frame
// number, so the map's drive and the queries' get independent errors, and the same scan always the
// same ones (a network's output is a function of its input).
constexpr uint64_t kDefaultNoiseSeed = 1;
uint64_t real_scan_seed(uint64_t noise_seed, const std::string& sequence, uint32_t frame);

}  // namespace gsf::label_errors
