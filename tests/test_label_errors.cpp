// Simulated network errors on ground-truth labels (tools/label_errors), per label space: point noise
// rate and partners, whole-object confusion (by instance id and by grid components), determinism
// whatever the point order, P = 0 changes nothing, nuScenes thin misses are a no-op, spurious objects.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <map>
#include <numeric>
#include <vector>

#include "gsf/detail/rng.h"
#include "label_errors/label_errors.h"

namespace test_label_errors {

using namespace gsf::label_errors;

namespace {

// A synthetic scan: points and their label words, built object by object.
struct Scan {
  std::vector<float> xyzi;
  std::vector<uint32_t> labels;
  uint32_t size() const { return static_cast<uint32_t>(labels.size()); }
  void add(float x, float y, float z, uint32_t label) {
    xyzi.insert(xyzi.end(), {x, y, z, 0.5f});
    labels.push_back(label);
  }
  // A vertical post of radius ~0.1 m at (x, y), 0..height m, 40 points.
  void post(float x, float y, float height, uint32_t label) {
    for (int k = 0; k < 40; ++k)
      add(x + 0.1f * std::cos(k * 1.3f), y + 0.1f * std::sin(k * 1.3f), height * k / 40, label);
  }
  // A box of points (a car, a wall) from (x0, y0) spanning dx x dy x dz, sampled every 0.25 m.
  void box(float x0, float y0, float dx, float dy, float dz, uint32_t label) {
    for (float x = 0; x <= dx; x += 0.25f)
      for (float y = 0; y <= dy; y += 0.25f)
        for (float z = 0; z <= dz; z += 0.25f) add(x0 + x, y0 + y, z, label);
  }
};

bool is_partner(uint16_t of, uint16_t cls, LabelSpace space) {
  for (int k = 0; k < label_partner_count(of, space); ++k)
    if (label_partner(of, k, space) == cls) return true;
  return false;
}

// Share of points changed by point noise at rate p, and whether every change went to a partner with the
// instance bits kept.
double noise_rate(const std::vector<uint32_t>& clean, float p, LabelSpace space, bool* only_partners) {
  std::vector<uint32_t> noisy = clean;
  apply_label_noise(noisy.data(), static_cast<uint32_t>(noisy.size()), p, 77, space);
  size_t changed = 0;
  *only_partners = true;
  for (size_t i = 0; i < clean.size(); ++i) {
    if (noisy[i] == clean[i]) continue;
    ++changed;
    *only_partners = *only_partners && (noisy[i] >> 16) == (clean[i] >> 16) &&
                     is_partner(clean[i] & 0xFFFF, noisy[i] & 0xFFFF, space);
  }
  return double(changed) / double(clean.size());
}

// The one class written for each group of points (group -> class); false if a group got two.
bool one_class_per_group(const std::vector<uint32_t>& labels, const std::vector<int>& group,
                         std::map<int, uint16_t>* out) {
  for (size_t i = 0; i < labels.size(); ++i) {
    if (group[i] < 0) continue;
    const auto it = out->emplace(group[i], labels[i] & 0xFFFF).first;
    if (it->second != (labels[i] & 0xFFFF)) return false;
  }
  return true;
}

// Applies object confusion to the scan with its points in the order `perm`, and returns the labels in the
// scan's own order.
std::vector<uint32_t> confused_in_order(const Scan& s, const std::vector<uint32_t>& perm, LabelSpace space,
                                        uint64_t seed) {
  Scan p;
  for (uint32_t i : perm) p.add(s.xyzi[4 * i], s.xyzi[4 * i + 1], s.xyzi[4 * i + 2], s.labels[i]);
  LabelErrorRates rates;
  rates.object_confusion = 0.5f;
  apply_label_errors(rates, space, p.xyzi.data(), p.labels.data(), p.size(), seed);
  std::vector<uint32_t> back(s.size());
  for (size_t k = 0; k < perm.size(); ++k) back[perm[k]] = p.labels[k];
  return back;
}

// Three orders of n points: as built, reversed, shuffled (seeded Fisher-Yates).
std::vector<std::vector<uint32_t>> point_orders(uint32_t n) {
  std::vector<uint32_t> order(n);
  std::iota(order.begin(), order.end(), 0u);
  std::vector<uint32_t> reversed(order.rbegin(), order.rend()), shuffled = order;
  gsf::Rng rng(2024);
  for (uint32_t i = n; i > 1; --i) std::swap(shuffled[i - 1], shuffled[rng.uniform(i)]);
  return {order, reversed, shuffled};
}

}  // namespace

TEST_CASE("Point noise: rate near P, only to partner classes, instance bits kept; P = 0 changes nothing") {
  std::vector<uint32_t> kitti, nus;
  const uint16_t kitti_classes[] = {40, 48, 50, 70, 72, 80, 10};
  const uint16_t nus_classes[] = {24, 26, 27, 28, 30, 17, 9};
  for (int i = 0; i < 14000; ++i) {
    kitti.push_back(kitti_classes[i % 7] | (uint32_t(i % 3) << 16));
    nus.push_back(nus_classes[i % 7]);
  }
  bool only_partners = false;
  CHECK(noise_rate(kitti, 0.0f, LabelSpace::SemanticKitti, &only_partners) == 0.0);
  CHECK(noise_rate(nus, 0.0f, LabelSpace::NuScenesLidarseg, &only_partners) == 0.0);
  const double rk = noise_rate(kitti, 0.1f, LabelSpace::SemanticKitti, &only_partners);
  CHECK(only_partners);
  const double rn = noise_rate(nus, 0.15f, LabelSpace::NuScenesLidarseg, &only_partners);
  CHECK(only_partners);
  INFO("SemanticKITTI rate " << rk << ", nuScenes rate " << rn);
  CHECK(std::fabs(rk - 0.10) < 0.012);
  CHECK(std::fabs(rn - 0.15) < 0.015);
}

TEST_CASE("nuScenes-lidarseg partner table: the documented pairs, both ways; noise, ego and animals have none") {
  const LabelSpace n = LabelSpace::NuScenesLidarseg;
  for (auto pr : {std::pair<int, int>{17, 23}, {24, 26}, {27, 30}, {28, 30}, {12, 9}, {14, 21}}) {
    CHECK(label_partner(pr.first, 0, n) == pr.second);  // the likelier partner
    CHECK(is_partner(pr.second, pr.first, n));
  }
  CHECK(label_partner(9, 0, n) == 28);  // a barrier is called manmade (not the other way round: walls are not barriers)
  CHECK(is_partner(24, 25, n));
  CHECK(is_partner(28, 29, n));
  for (uint16_t c : {0, 1, 31}) CHECK(label_partner_count(c, n) == 0);
  for (uint16_t c = 2; c <= 30; ++c) {
    CHECK(label_partner_count(c, n) > 0);
    for (int k = 0; k < label_partner_count(c, n); ++k) CHECK(label_partner(c, k, n) <= 30);
  }
}

TEST_CASE("SemanticKITTI object confusion: instances by id and id-less poles by component, whole, to one partner") {
  Scan s;
  std::vector<int> group;  // object of each point (-1: stuff)
  auto tag = [&](int g) { group.resize(s.size(), g); };
  for (int c = 0; c < 3; ++c) s.box(6.0f * c, 5.0f, 4.0f, 1.8f, 1.5f, 10u | uint32_t(c + 1) << 16), tag(c);
  for (int p = 0; p < 4; ++p) s.post(4.0f * p, -4.0f, 6.0f, 80), tag(10 + p);  // no instance id, as real labels
  s.post(20.0f, -4.0f, 3.0f, 71), tag(20);
  s.box(-5.0f, -2.0f, 30.0f, 3.0f, 0.0f, 40), tag(-1);  // road: stuff
  const std::vector<uint32_t> clean = s.labels;
  LabelErrorRates rates;
  rates.object_confusion = 0.0f;
  apply_label_errors(rates, LabelSpace::SemanticKitti, s.xyzi.data(), s.labels.data(), s.size(), 9);
  CHECK(s.labels == clean);
  rates.object_confusion = 1.0f;
  apply_label_errors(rates, LabelSpace::SemanticKitti, s.xyzi.data(), s.labels.data(), s.size(), 9);
  std::map<int, uint16_t> written;
  REQUIRE(one_class_per_group(s.labels, group, &written));
  REQUIRE(written.size() == 8);
  for (size_t i = 0; i < clean.size(); ++i) {
    CHECK((s.labels[i] >> 16) == (clean[i] >> 16));  // instance bits kept
    if (group[i] < 0) CHECK(s.labels[i] == clean[i]);
    else CHECK(is_partner(clean[i] & 0xFFFF, s.labels[i] & 0xFFFF, LabelSpace::SemanticKitti));
  }
}

TEST_CASE("nuScenes object confusion: thing components and thin manmade / vegetation, whole; walls and ground kept") {
  Scan s;
  std::vector<int> group;
  auto tag = [&](int g) { group.resize(s.size(), g); };
  s.box(0.0f, 5.0f, 4.0f, 1.8f, 1.5f, 17), tag(0);        // car
  s.box(8.0f, 5.0f, 7.0f, 2.4f, 2.5f, 23), tag(1);        // truck
  s.box(0.0f, -6.0f, 0.5f, 0.5f, 1.0f, 9), tag(2);        // barrier
  s.post(3.0f, 0.0f, 6.0f, 28), tag(3);                   // pole: thin static.manmade
  s.post(9.0f, 0.0f, 3.0f, 30), tag(4);                   // trunk: thin static.vegetation
  s.box(-10.0f, 12.0f, 12.0f, 0.25f, 3.0f, 28), tag(-1);  // wall: static.manmade, not thin
  s.box(-5.0f, -2.0f, 20.0f, 3.0f, 0.0f, 24), tag(-1);    // driveable surface
  const std::vector<uint32_t> clean = s.labels;
  LabelErrorRates rates;
  rates.object_confusion = 1.0f;
  apply_label_errors(rates, LabelSpace::NuScenesLidarseg, s.xyzi.data(), s.labels.data(), s.size(), 3);
  std::map<int, uint16_t> written;
  REQUIRE(one_class_per_group(s.labels, group, &written));
  REQUIRE(written.size() == 5);
  for (size_t i = 0; i < clean.size(); ++i) {
    if (group[i] < 0) CHECK(s.labels[i] == clean[i]);
    else CHECK(is_partner(clean[i], s.labels[i], LabelSpace::NuScenesLidarseg));
  }
  // At P = 0.3, over many scans (seeds), about 30% of the five objects are relabelled.
  int confused = 0, draws = 0;
  rates.object_confusion = 0.3f;
  for (uint64_t seed = 0; seed < 200; ++seed) {
    std::vector<uint32_t> l = clean;
    apply_label_errors(rates, LabelSpace::NuScenesLidarseg, s.xyzi.data(), l.data(), s.size(), seed);
    for (int g = 0; g < 5; ++g) {
      const size_t first = std::find(group.begin(), group.end(), g) - group.begin();
      confused += l[first] != clean[first];
      ++draws;
    }
  }
  INFO(confused << " of " << draws);
  CHECK(std::fabs(double(confused) / draws - 0.3) < 0.05);
}

TEST_CASE("Object confusion is the same whatever the point order; same seed, same labels; seeds differ by scan") {
  Scan s, k;
  for (int p = 0; p < 12; ++p) s.post(3.0f * p, 2.0f, 5.0f, 28), k.post(3.0f * p, 2.0f, 5.0f, 80);
  for (int c = 0; c < 6; ++c)
    s.box(5.0f * c, -6.0f, 4.0f, 1.8f, 1.5f, 17), k.box(5.0f * c, -6.0f, 4.0f, 1.8f, 1.5f, 10);
  const std::vector<std::vector<uint32_t>> orders = point_orders(s.size());
  for (const LabelSpace space : {LabelSpace::NuScenesLidarseg, LabelSpace::SemanticKitti}) {
    const Scan& scan = space == LabelSpace::NuScenesLidarseg ? s : k;  // id-less poles and cars in both
    const std::vector<uint32_t> a = confused_in_order(scan, orders[0], space, 42);
    CHECK(a != scan.labels);  // something was confused at P = 0.5 over 18 objects
    CHECK(confused_in_order(scan, orders[0], space, 42) == a);
    CHECK(confused_in_order(scan, orders[1], space, 42) == a);  // reversed
    CHECK(confused_in_order(scan, orders[2], space, 42) == a);  // shuffled
    CHECK(confused_in_order(scan, orders[0], space, 43) != a);
  }
  // Scan seeds: by noise seed, sequence name and frame.
  const uint64_t base = real_scan_seed(kDefaultNoiseSeed, "0002", 7);
  CHECK(real_scan_seed(kDefaultNoiseSeed, "0002", 7) == base);
  CHECK(real_scan_seed(kDefaultNoiseSeed, "0004", 7) != base);
  CHECK(real_scan_seed(kDefaultNoiseSeed, "0002", 8) != base);
  CHECK(real_scan_seed(kDefaultNoiseSeed + 1, "0002", 7) != base);
}

TEST_CASE("Thin misses act on SemanticKITTI poles far away and are a no-op on nuScenes-lidarseg labels") {
  Scan kitti, nus;
  for (int p = 0; p < 10; ++p) {
    kitti.post(70.0f, 3.0f * p, 6.0f, 80);  // beyond kThinMissFar: missed at rate P
    nus.post(70.0f, 3.0f * p, 6.0f, 28);
  }
  LabelErrorRates rates;
  rates.thin_miss = 1.0f;
  const std::vector<uint32_t> nus_clean = nus.labels;
  apply_label_errors(rates, LabelSpace::NuScenesLidarseg, nus.xyzi.data(), nus.labels.data(), nus.size(), 1);
  CHECK(nus.labels == nus_clean);
  apply_label_errors(rates, LabelSpace::SemanticKitti, kitti.xyzi.data(), kitti.labels.data(), kitti.size(), 1);
  CHECK(std::all_of(kitti.labels.begin(), kitti.labels.end(), [](uint32_t l) { return l == 50u; }));
}

TEST_CASE("Spurious objects: round(P x instances) wall or hedge patches in range become poles or trunks") {
  Scan s;
  for (int p = 0; p < 4; ++p) s.post(8.0f + 2.0f * p, -6.0f, 5.0f, (uint32_t(p + 1) << 16) | 80u);  // 4 instances
  s.box(6.0f, 10.0f, 20.0f, 0.5f, 4.0f, 50);    // a wall 10 m away: in range
  s.box(-30.0f, 50.0f, 20.0f, 0.5f, 4.0f, 70);  // a hedge beyond kSpuriousFar: never chosen
  s.box(5.0f, -2.0f, 12.0f, 12.0f, 0.0f, 40);   // road: never relabelled
  const std::vector<uint32_t> clean = s.labels;

  std::vector<uint32_t> none = clean;
  apply_spurious_objects(s.xyzi.data(), none.data(), s.size(), 0.0f, 3);
  CHECK(none == clean);

  std::vector<uint32_t> labels = clean;
  apply_spurious_objects(s.xyzi.data(), labels.data(), s.size(), 0.5f, 3);  // 0.5 x 4 instances: 2 patches
  std::map<uint32_t, std::vector<uint32_t>> patches;                        // spurious instance id -> its points
  for (uint32_t i = 0; i < s.size(); ++i) {
    if (labels[i] == clean[i]) continue;
    REQUIRE((clean[i] & 0xFFFF) == 50u);  // only the wall in range changes, to pole with a new instance id
    CHECK((labels[i] & 0xFFFF) == 80u);
    CHECK((labels[i] >> 16) >= kSpuriousInstanceBase);
    patches[labels[i] >> 16].push_back(i);
  }
  REQUIRE(patches.size() == 2);
  for (const auto& [id, points] : patches) {  // each patch: within 2 x kSpuriousRadius across, horizontally
    for (uint32_t a : points)
      for (uint32_t b : points)
        CHECK(std::hypot(s.xyzi[4 * a] - s.xyzi[4 * b], s.xyzi[4 * a + 1] - s.xyzi[4 * b + 1]) <=
              2.0f * kSpuriousRadius + 1e-4f);
  }
  std::vector<uint32_t> again = clean;
  apply_spurious_objects(s.xyzi.data(), again.data(), s.size(), 0.5f, 3);
  CHECK(again == labels);  // the same seed, the same patches
}

}  // namespace test_label_errors
