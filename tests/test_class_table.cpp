// Class tables: the built-in SemanticKITTI table reproduces class_from_kitti()/stability_weight() for
// every raw id; the nuScenes-lidarseg table reproduces the port's mapping; add() validation; the table
// id (stable values, what changes it and what does not); the text format parser (every error with its
// line, limits, round trip) and loading from a file.
#include <catch2/catch.hpp>

#include <cmath>
#include <fstream>
#include <string>

#include "gsf/class_table.h"
#include "gsf/port/class_table_file.h"
#include "gsf/port/nuscenes.h"

namespace test_class_table {

using namespace gsf;

TEST_CASE("SemanticKITTI table equals class_from_kitti and stability_weight for every id") {
  ClassTable t;
  semantic_kitti_class_table(&t);
  CHECK(t.size() == 34);
  uint32_t mismatches = 0;
  for (uint32_t id = 0; id <= 0xFFFFu; ++id) {
    mismatches += t.library_class(id) != class_from_kitti(id);
    // The high 16 bits (instance id) are ignored, as by class_from_kitti.
    mismatches += t.library_class(id | 0xABCD0000u) != class_from_kitti(id | 0xABCD0000u);
  }
  CHECK(mismatches == 0);
  for (int c = -3; c < kNumClasses + 3; ++c) {
    INFO("class " << c);
    CHECK(t.stability(c) == stability_weight(c));
  }
  CHECK(t.instance_classes() == kDefaultInstanceClasses);
  CHECK(t.pole_host_classes() == 0);
  CHECK(t.trunk_host_classes() == 0);
  CHECK((t.stuff_classes() | t.instance_classes()) == (1u << kNumClasses) - 1);
  CHECK(t.mapped_classes() == (1u << kNumClasses) - 1);
  // Every id the table lists maps back to its canonical id's class.
  for (uint32_t i = 0; i < t.size(); ++i) {
    const ClassTableEntry& e = t.entry(i);
    if (e.library_class >= 0) CHECK(class_from_kitti(kitti_from_class(e.library_class)) == e.library_class);
  }
}

TEST_CASE("nuScenes-lidarseg table equals the port's nuScenes -> SemanticKITTI mapping") {
  ClassTable t;
  nuscenes_lidarseg_class_table(&t);
  CHECK(t.size() == 32);
  for (uint32_t c = 0; c < 32; ++c) {
    INFO("nuScenes class " << c << " " << t.find(c)->name);
    CHECK(t.library_class(c) == class_from_kitti(port::nuscenes_to_kitti(static_cast<uint8_t>(c))));
  }
  for (uint32_t c = 32; c < 70000; ++c)
    if (c <= 0xFFFF) REQUIRE(t.library_class(c) == kUnknownClass);
  CHECK(t.pole_host_classes() == class_bit(kBuilding));
  CHECK(t.trunk_host_classes() == class_bit(kVegetation));
  CHECK(t.role(kCar) == ClassRole::Instance);
  CHECK((t.instance_classes() & class_bit(kCar)) != 0);
  CHECK(std::string(t.find(28)->name) == "static.manmade");
  CHECK(std::string(t.find(30)->name) == "static.vegetation");
  CHECK(std::string(t.find(4)->name) == "human.pedestrian.construction_worker");
  for (int c = 0; c < kNumClasses; ++c) CHECK(t.stability(c) == stability_weight(c));
}

TEST_CASE("Table ids are stable, ignore names and insertion order, and see every mapping change") {
  ClassTable kitti, nusc;
  semantic_kitti_class_table(&kitti);
  nuscenes_lidarseg_class_table(&nusc);
  // Pinned: a map records these; changing them silently would orphan every map built before.
  CHECK(kitti.id() == 0xf1d8dab4u);
  CHECK(nusc.id() == 0xcb246e6bu);
  CHECK(kitti.id() != nusc.id());

  ClassTable a, b;
  REQUIRE(a.add(10, "car", kCar, 0.5f, ClassRole::Instance) == ClassTableError::None);
  REQUIRE(a.add(50, "building", kBuilding, 1.0f, ClassRole::PoleHost) == ClassTableError::None);
  REQUIRE(b.add(50, "wall-and-poles", kBuilding, 1.0f, ClassRole::PoleHost) == ClassTableError::None);
  REQUIRE(b.add(10, "automobile", kCar, 0.5f, ClassRole::Instance) == ClassTableError::None);
  CHECK(a.id() == b.id());
  ClassTable c = a;
  c.clear();
  REQUIRE(c.add(10, "car", kCar, 0.5f, ClassRole::Instance) == ClassTableError::None);
  REQUIRE(c.add(50, "building", kBuilding, 0.9f, ClassRole::PoleHost) == ClassTableError::None);
  CHECK(c.id() != a.id());
  c.clear();
  REQUIRE(c.add(10, "car", kCar, 0.5f, ClassRole::Instance) == ClassTableError::None);
  REQUIRE(c.add(50, "building", kBuilding, 1.0f, ClassRole::TrunkHost) == ClassTableError::None);
  CHECK(c.id() != a.id());
  c.clear();
  REQUIRE(c.add(10, "car", kCar, 0.5f, ClassRole::Instance) == ClassTableError::None);
  REQUIRE(c.add(51, "building", kBuilding, 1.0f, ClassRole::PoleHost) == ClassTableError::None);
  CHECK(c.id() != a.id());
  c.clear();
  REQUIRE(c.add(10, "car", kTruck, 0.5f, ClassRole::Instance) == ClassTableError::None);
  REQUIRE(c.add(50, "building", kBuilding, 1.0f, ClassRole::PoleHost) == ClassTableError::None);
  CHECK(c.id() != a.id());
}

TEST_CASE("ClassTable::add validates every entry and leaves the table unchanged on error") {
  ClassTable t;
  REQUIRE(t.add(10, "car", kCar, 0.5f, ClassRole::Instance) == ClassTableError::None);
  const uint32_t id = t.id();
  CHECK(t.add(10, "again", kCar, 0.5f, ClassRole::Instance) == ClassTableError::DuplicateId);
  CHECK(t.add(11, "x", kNumClasses, 0.5f, ClassRole::Stuff) == ClassTableError::BadClass);
  CHECK(t.add(11, "x", kUnknownClass, 0.5f, ClassRole::Stuff) == ClassTableError::BadClass);
  CHECK(t.add(11, "x", kBicycle, 1.5f, ClassRole::Stuff) == ClassTableError::BadStability);
  CHECK(t.add(11, "x", kBicycle, -0.1f, ClassRole::Stuff) == ClassTableError::BadStability);
  CHECK(t.add(11, "x", kBicycle, std::nanf(""), ClassRole::Stuff) == ClassTableError::BadStability);
  CHECK(t.add(11, "x", kBicycle, 0.1f, static_cast<ClassRole>(9)) == ClassTableError::BadRole);
  CHECK(t.add(0, "x", kIgnoredClass, 0.0f, ClassRole::Instance) == ClassTableError::BadRole);
  CHECK(t.add(252, "moving-car", kCar, 0.4f, ClassRole::Instance) == ClassTableError::ConflictingStability);
  CHECK(t.add(252, "moving-car", kCar, 0.5f, ClassRole::Stuff) == ClassTableError::ConflictingRole);
  CHECK(t.add(11, "0123456789012345678901234567890123456789", kBicycle, 0.1f, ClassRole::Stuff) ==
        ClassTableError::NameTooLong);
  CHECK(t.size() == 1);
  CHECK(t.id() == id);
  CHECK(t.add(252, "moving-car", kCar, 0.5f, ClassRole::Instance) == ClassTableError::None);
  ClassTable full;
  for (uint32_t i = 0; i < kMaxClassTableEntries; ++i)
    REQUIRE(full.add(static_cast<uint16_t>(1000 - i), "", kIgnoredClass, 0.0f, ClassRole::Stuff) ==
            ClassTableError::None);
  CHECK(full.add(5, "", kIgnoredClass, 0.0f, ClassRole::Stuff) == ClassTableError::TooManyEntries);
  for (uint32_t i = 1; i < full.size(); ++i) CHECK(full.entry(i - 1).raw_id < full.entry(i).raw_id);
  CHECK(full.library_class(1000) == kIgnoredClass);
  CHECK(full.library_class(1001) == kUnknownClass);
  CHECK(full.library_class(744) == kUnknownClass);
}

namespace {
Status parse(const std::string& text, ClassTable* t, port::ClassTableParseError* e) {
  return port::parse_class_table(text.data(), text.size(), t, e);
}
}  // namespace

TEST_CASE("Class table text: a valid file with comments, tabs, CRLF and default roles") {
  const std::string text =
      "# my label set\n"
      "\n"
      "   # indented comment\n"
      "0 unlabeled ignored 0\n"
      "17\tvehicle.car\tcar\t0.5\tinstance   # trailing comment\r\n"
      "18 vehicle.parked car .5\n"  // role: what car already has
      "28 static.manmade building 1 host:pole\n"
      "30 static.vegetation vegetation 0.50 host:trunk\n"
      "80 pole pole 1.0\n"  // role: library default (instance)
      "24 road road 1.0\n"
      "65535 last ignored 0.0";  // no final newline
  ClassTable t;
  port::ClassTableParseError e;
  REQUIRE(parse(text, &t, &e) == Status::Ok);
  CHECK(t.size() == 8);
  CHECK(t.library_class(17) == kCar);
  CHECK(t.library_class(18) == kCar);
  CHECK(t.library_class(0) == kIgnoredClass);
  CHECK(t.library_class(65535) == kIgnoredClass);
  CHECK(t.library_class(1) == kUnknownClass);
  CHECK(t.role(kCar) == ClassRole::Instance);
  CHECK(t.role(kPole) == ClassRole::Instance);
  CHECK(t.role(kRoad) == ClassRole::Stuff);
  CHECK(t.pole_host_classes() == class_bit(kBuilding));
  CHECK(t.trunk_host_classes() == class_bit(kVegetation));
  CHECK(t.stability(kCar) == 0.5f);
  CHECK(std::string(t.find(17)->name) == "vehicle.car");

  // Round trip: format -> parse gives the same id (built-ins too).
  ClassTable back;
  REQUIRE(parse(port::format_class_table(t), &back, &e) == Status::Ok);
  CHECK(back.id() == t.id());
  ClassTable nusc, kitti;
  nuscenes_lidarseg_class_table(&nusc);
  semantic_kitti_class_table(&kitti);
  REQUIRE(parse(port::format_class_table(nusc), &back, &e) == Status::Ok);
  CHECK(back.id() == nusc.id());
  REQUIRE(parse(port::format_class_table(kitti), &back, &e) == Status::Ok);
  CHECK(back.id() == kitti.id());
  // Weights that need many decimals survive the round trip exactly.
  ClassTable odd;
  REQUIRE(parse("1 a car 0.00000000001\n2 b road 0.12345678901\n3 c pole 0.3\n", &odd, &e) == Status::Ok);
  REQUIRE(parse(port::format_class_table(odd), &back, &e) == Status::Ok);
  CHECK(back.id() == odd.id());
  CHECK(back.stability(kRoad) == odd.stability(kRoad));
  CHECK(odd.stability(kPole) == 0.3f);
  // Twelve decimals and no leading zero (fuzz_class_table found that 11 decimals lost this weight).
  ClassTable twelve;
  REQUIRE(parse("4 a road .000040400407\n", &twelve, &e) == Status::Ok);
  const std::string twelve_text = port::format_class_table(twelve);
  INFO(twelve_text);
  REQUIRE(parse(twelve_text, &back, &e) == Status::Ok);
  CHECK(back.id() == twelve.id());
  CHECK(back.stability(kRoad) == twelve.stability(kRoad));
}

TEST_CASE("Class table text: every defect is rejected with its status, line and field") {
  struct Case {
    const char* text;
    Status status;
    uint32_t line, field;
    const char* says;
  };
  const std::string long_line = "1 a car 0.5 #" + std::string(300, 'x') + "\n";
  const Case cases[] = {
      {"", Status::CorruptData, 0, 0, "no entries"},
      {"# only a comment\n\n", Status::CorruptData, 0, 0, "no entries"},
      {"1 a car 0.5\n1 b car 0.5\n", Status::CorruptData, 2, 1, "duplicate"},
      {"1 a car 0.5\n2 b polee 0.5\n", Status::CorruptData, 2, 3, "unknown library class"},
      {"1 a Car 0.5\n", Status::CorruptData, 1, 3, "unknown library class"},
      {"1 a car 1.5\n", Status::CorruptData, 1, 4, "outside [0, 1]"},
      {"1 a car -0.5\n", Status::CorruptData, 1, 4, "plain decimal"},
      {"1 a car 5e-1\n", Status::CorruptData, 1, 4, "plain decimal"},
      {"1 a car nan\n", Status::CorruptData, 1, 4, "plain decimal"},
      {"1 a car .\n", Status::CorruptData, 1, 4, "plain decimal"},
      {"1 a car 0.1.2\n", Status::CorruptData, 1, 4, "plain decimal"},
      {"1 a car 0.0000000000001\n", Status::CorruptData, 1, 4, "plain decimal"},
      {"x a car 0.5\n", Status::CorruptData, 1, 1, "0..65535"},
      {"-1 a car 0.5\n", Status::CorruptData, 1, 1, "0..65535"},
      {"65536 a car 0.5\n", Status::CorruptData, 1, 1, "0..65535"},
      {"123456 a car 0.5\n", Status::CorruptData, 1, 1, "0..65535"},
      {"1 a car\n", Status::CorruptData, 1, 4, "missing field"},
      {"\n\n1\n", Status::CorruptData, 3, 2, "missing field"},
      {"1 a car 0.5 instance extra\n", Status::CorruptData, 1, 6, "too many fields"},
      {"1 a car 0.5 host:tree\n", Status::CorruptData, 1, 5, "unknown role"},
      {"1 a ignored 0 instance\n", Status::CorruptData, 1, 5, "ignored"},
      {"1 a car 0.5\n2 b car 0.4\n", Status::CorruptData, 2, 4, "stability differs"},
      {"1 a car 0.5 instance\n2 b car 0.5 stuff\n", Status::CorruptData, 2, 5, "role differs"},
      {"1 0123456789012345678901234567890123456789 car 0.5\n", Status::CorruptData, 1, 2, "longer than 39"},
      {"1 a car 0.5\n2 b\x01 road 1\n", Status::CorruptData, 2, 0, "control"},
      {"1 a car 0.5\n2 b\xc3\xa9 road 1\n", Status::CorruptData, 2, 0, "non-ASCII"},
  };
  for (const Case& c : cases) {
    const std::string text(c.text);
    INFO("text: " << text);
    ClassTable t;
    REQUIRE(t.add(999, "stale", kCar, 0.5f, ClassRole::Instance) == ClassTableError::None);
    port::ClassTableParseError e;
    CHECK(parse(text, &t, &e) == c.status);
    CHECK(e.line == c.line);
    CHECK(e.field == c.field);
    CHECK(std::string(e.message).find(c.says) != std::string::npos);
    CHECK(t.size() == 0);  // cleared, never half-filled or stale
  }
  ClassTable t;
  port::ClassTableParseError e;
  // An embedded NUL byte is a control character, not the end of the text.
  CHECK(parse(std::string("1 a car 0.5\n2 b road 1\0\n", 24), &t, &e) == Status::CorruptData);
  CHECK(e.line == 2);
  CHECK(parse(std::string("1 a car 0.5 # comment \0 may hold anything\n", 42), &t, &e) == Status::Ok);
  // Limits.
  CHECK(parse("1 a car 0.5\n" + long_line, &t, &e) == Status::CapacityExceeded);
  CHECK(e.line == 2);
  CHECK(std::string(e.message).find("256 bytes") != std::string::npos);
  std::string ok_long = "1 a car 0.5 " + std::string(256 - 12, ' ') + "\n";  // exactly 256 bytes
  REQUIRE(ok_long.size() == 257);
  CHECK(parse(ok_long, &t, &e) == Status::Ok);
  std::string many;
  for (int i = 0; i < 4096; ++i) many += i == 0 ? "1 a car 0.5\n" : "#\n";
  CHECK(parse(many, &t, &e) == Status::Ok);
  many += "#\n";
  CHECK(parse(many, &t, &e) == Status::CapacityExceeded);
  CHECK(e.line == 4097);
  std::string entries;
  for (int i = 0; i < 257; ++i) entries += std::to_string(i) + " n ignored 0\n";
  CHECK(parse(entries, &t, &e) == Status::CapacityExceeded);
  CHECK(e.line == 257);
  CHECK(std::string(e.message).find("256 entries") != std::string::npos);
  CHECK(port::parse_class_table(nullptr, 3, &t, &e) == Status::InvalidArgument);
  CHECK(port::parse_class_table("1 a car 0.5", 11, nullptr, &e) == Status::InvalidArgument);
}

TEST_CASE("Class table file: load from disk, missing file, the nuScenes example in docs") {
  const std::string path = std::string(GSF_TEST_TMP_DIR) + "/nuscenes_table.txt";
  ClassTable nusc;
  nuscenes_lidarseg_class_table(&nusc);
  {
    std::ofstream f(path);
    f << port::format_class_table(nusc);
  }
  ClassTable t;
  port::ClassTableParseError e;
  REQUIRE(port::load_class_table(path, &t, &e) == Status::Ok);
  CHECK(t.id() == nusc.id());
  CHECK(port::load_class_table(path + ".missing", &t, &e) == Status::NotFound);
  CHECK(t.size() == 0);
  // The seed corpus of the fuzz target is the documented nuScenes example: it must parse.
  REQUIRE(port::load_class_table(std::string(GSF_SOURCE_DIR) + "/fuzz/corpus/fuzz_class_table/nuscenes.txt", &t, &e) ==
          Status::Ok);
  CHECK(t.id() == nusc.id());
}

}  // namespace test_class_table
