// A user label set as text: one line per raw label id, loaded into a core ClassTable (gsf/class_table.h).
//
//   # comment (anything after '#' on a line is ignored; blank lines too)
//   <id> <name> <library_class> <stability> [instance|stuff|host:pole|host:trunk]
//   28   static.manmade      building   1.0  host:pole
//   30   static.vegetation   vegetation 0.5  host:trunk
//   17   vehicle.car         car        0.5  instance
//   0    noise               ignored    0
//
// Fields are separated by spaces or tabs; lines end in LF (a CR before it is dropped).
//   id            decimal 0..65535 (the low 16 bits of a label word), unique in the file
//   name          1..39 printable ASCII characters, no spaces (informational; not part of the table id)
//   library_class a class_name() of semantic_classes.h ("car", "traffic-sign", ...) or "ignored"
//   stability     plain decimal within [0, 1] ("1", "0.5", ".1"; no sign, no exponent, <= 12 digits)
//   role          optional; absent: the role the class already has in this file, else the library
//                 default (instance for car/trunk/pole/traffic-sign, stuff otherwise). An ignored
//                 class can only be stuff.
// All raw ids of one library class must agree on stability and role (core rule, ClassTable::add).
// Limits: 256 bytes per line (newline excluded), 4096 lines, kMaxClassTableEntries (256) entries.
//
// Statuses: Ok; CorruptData for anything malformed or invalid (non-numeric or out-of-range field,
// unknown class or role, missing or extra field, control or non-ASCII byte outside a comment,
// duplicate id, conflicting stability/role, no entries); CapacityExceeded for a line over 256 bytes,
// more than 4096 lines or more than 256 entries; IoError/NotFound from load_class_table() for the file.
// On any error *out is cleared and `error` (if given) holds the 1-based line (0 when the problem
// belongs to no single line, as "no entries"), the 1-based field (0: the whole line) and a static message.
// parse_class_table() does not allocate; load_class_table() reads the file into memory first (init time).
#pragma once
#include <cstddef>
#include <cstdint>
#include <string>

#include "gsf/class_table.h"
#include "gsf/status.h"

namespace gsf::port {

constexpr uint32_t kClassTableMaxLineBytes = 256;
constexpr uint32_t kClassTableMaxLines = 4096;

struct ClassTableParseError {
  uint32_t line = 0;
  uint32_t field = 0;
  const char* message = "";  // static storage, never null
};

Status parse_class_table(const char* text, size_t bytes, ClassTable* out, ClassTableParseError* error = nullptr);
Status load_class_table(const std::string& path, ClassTable* out, ClassTableParseError* error = nullptr);

// The table in the text format above (one line per entry, every role explicit, stability with up to 9
// decimals); parse_class_table() of it gives a table with the same id(). Allocates (host tools, tests).
std::string format_class_table(const ClassTable& table);

}  // namespace gsf::port
