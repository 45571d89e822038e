// Fuzz the class table text parser: any bytes give Ok (a valid table that round-trips through
// format_class_table with the same id) or CorruptData / CapacityExceeded with an emptied table and a
// line number within the limits.
#include <cstdint>
#include <string>

#include "gsf/port/class_table_file.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static gsf::ClassTable table, back;  // ~12 KB each: keep them off the fuzzer's stack
  gsf::port::ClassTableParseError e;
  const gsf::Status s = gsf::port::parse_class_table(reinterpret_cast<const char*>(data), size, &table, &e);
  if (e.message == nullptr) __builtin_trap();
  if (s != gsf::Status::Ok) {
    if (s != gsf::Status::CorruptData && s != gsf::Status::CapacityExceeded) __builtin_trap();
    if (table.size() != 0 || e.line > gsf::port::kClassTableMaxLines + 1) __builtin_trap();
    return 0;
  }
  if (table.size() == 0 || table.size() > gsf::kMaxClassTableEntries) __builtin_trap();
  for (uint32_t i = 0; i < table.size(); ++i) {
    const gsf::ClassTableEntry& en = table.entry(i);
    if (i > 0 && table.entry(i - 1).raw_id >= en.raw_id) __builtin_trap();
    if (table.find(en.raw_id) != &en) __builtin_trap();
    if (en.library_class != gsf::kIgnoredClass && (en.library_class < 0 || en.library_class >= gsf::kNumClasses))
      __builtin_trap();
    if (en.library_class >= 0 && table.role(en.library_class) != en.role) __builtin_trap();
  }
  for (int c = 0; c < gsf::kNumClasses; ++c)
    if (!(table.stability(c) >= 0.0f && table.stability(c) <= 1.0f)) __builtin_trap();
  const std::string text = gsf::port::format_class_table(table);
  if (gsf::port::parse_class_table(text.data(), text.size(), &back, &e) != gsf::Status::Ok) __builtin_trap();
  if (back.id() != table.id() || back.size() != table.size()) __builtin_trap();
  return 0;
}
