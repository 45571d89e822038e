#include "gsf/port/class_table_file.h"

#include <cstdio>
#include <cstring>
#include <vector>

#include "scan_files.h"

namespace gsf::port {
namespace {

struct Token {
  const char* p;
  uint32_t n;
};

bool fail(ClassTableParseError* e, uint32_t line, uint32_t field, const char* msg) {
  if (e) {
    e->line = line;
    e->field = field;
    e->message = msg;
  }
  return false;
}

bool is_space(char c) { return c == ' ' || c == '\t'; }

bool parse_id(Token t, uint16_t* out) {
  if (t.n == 0 || t.n > 5) return false;
  uint32_t v = 0;
  for (uint32_t i = 0; i < t.n; ++i) {
    if (t.p[i] < '0' || t.p[i] > '9') return false;
    v = v * 10 + uint32_t(t.p[i] - '0');
  }
  if (v > 65535) return false;
  *out = static_cast<uint16_t>(v);
  return true;
}

// D+[.D*] or .D+ with at most 12 digits; exact decimal -> nearest double -> float.
bool parse_decimal(Token t, float* out) {
  uint64_t mantissa = 0;
  uint32_t digits = 0, frac = 0;
  bool dot = false;
  for (uint32_t i = 0; i < t.n; ++i) {
    const char c = t.p[i];
    if (c == '.') {
      if (dot) return false;
      dot = true;
    } else if (c >= '0' && c <= '9') {
      if (++digits > 12) return false;
      mantissa = mantissa * 10 + uint64_t(c - '0');
      if (dot) ++frac;
    } else {
      return false;
    }
  }
  if (digits == 0) return false;
  double scale = 1.0;
  for (uint32_t i = 0; i < frac; ++i) scale *= 10.0;  // exact up to 1e12
  *out = static_cast<float>(static_cast<double>(mantissa) / scale);
  return true;
}

bool parse_role(Token t, ClassRole* out) {
  struct R {
    const char* s;
    ClassRole r;
  };
  static const R kRoles[] = {{"instance", ClassRole::Instance},
                             {"stuff", ClassRole::Stuff},
                             {"host:pole", ClassRole::PoleHost},
                             {"host:trunk", ClassRole::TrunkHost}};
  for (const R& r : kRoles)
    if (std::strlen(r.s) == t.n && std::memcmp(r.s, t.p, t.n) == 0) {
      *out = r.r;
      return true;
    }
  return false;
}

const char* core_message(ClassTableError e) {
  switch (e) {
    case ClassTableError::DuplicateId: return "duplicate raw id";
    case ClassTableError::BadStability: return "stability outside [0, 1]";
    case ClassTableError::BadRole: return "an ignored class can only be stuff";
    case ClassTableError::ConflictingStability:
      return "stability differs from an earlier line of the same library class";
    case ClassTableError::ConflictingRole: return "role differs from an earlier line of the same library class";
    case ClassTableError::NameTooLong: return "name longer than 39 characters";
    case ClassTableError::TooManyEntries: return "more than 256 entries";
    default: return to_string(e);
  }
}

// One line (without its newline), already checked for length. false + error on failure.
bool parse_line(const char* p, uint32_t n, uint32_t line, ClassTable* out, ClassTableParseError* err, Status* status) {
  *status = Status::CorruptData;
  // Cut the comment and a trailing CR; reject control and non-ASCII bytes in what remains.
  for (uint32_t i = 0; i < n; ++i)
    if (p[i] == '#') {
      n = i;
      break;
    }
  if (n > 0 && p[n - 1] == '\r') --n;
  for (uint32_t i = 0; i < n; ++i) {
    const unsigned char c = static_cast<unsigned char>(p[i]);
    if ((c < 0x20 && c != '\t') || c >= 0x7F) return fail(err, line, 0, "control or non-ASCII character");
  }
  Token f[5];
  uint32_t nf = 0;
  for (uint32_t i = 0; i < n;) {
    while (i < n && is_space(p[i])) ++i;
    if (i == n) break;
    const uint32_t start = i;
    while (i < n && !is_space(p[i])) ++i;
    if (nf == 5) return fail(err, line, 6, "too many fields (expected: id name library_class stability [role])");
    f[nf++] = Token{p + start, i - start};
  }
  if (nf == 0) {
    *status = Status::Ok;
    return true;
  }  // blank or comment-only
  if (nf < 4) return fail(err, line, nf + 1, "missing field (expected: id name library_class stability [role])");
  uint16_t id;
  if (!parse_id(f[0], &id)) return fail(err, line, 1, "id is not a decimal integer in 0..65535");
  if (f[1].n >= kClassTableNameBytes) return fail(err, line, 2, "name longer than 39 characters");
  const int cls = library_class_from_name(f[2].p, f[2].n);
  if (cls == kUnknownClass) return fail(err, line, 3, "unknown library class (see docs/data-formats.md)");
  float stability;
  if (!parse_decimal(f[3], &stability)) return fail(err, line, 4, "stability is not a plain decimal number");
  ClassRole role = cls == kIgnoredClass ? ClassRole::Stuff : out->role(cls);
  if (nf == 5 && !parse_role(f[4], &role))
    return fail(err, line, 5, "unknown role (instance, stuff, host:pole or host:trunk)");
  char name[kClassTableNameBytes];
  std::memcpy(name, f[1].p, f[1].n);
  name[f[1].n] = '\0';
  const ClassTableError e = out->add(id, name, cls, stability, role);
  if (e != ClassTableError::None) {
    if (e == ClassTableError::TooManyEntries) *status = Status::CapacityExceeded;
    const uint32_t field = e == ClassTableError::DuplicateId                                                  ? 1
                           : e == ClassTableError::BadStability || e == ClassTableError::ConflictingStability ? 4
                           : e == ClassTableError::BadRole || e == ClassTableError::ConflictingRole           ? 5
                           : e == ClassTableError::NameTooLong                                                ? 2
                                                                                                              : 0;
    return fail(err, line, field, core_message(e));
  }
  *status = Status::Ok;
  return true;
}

}  // namespace

Status parse_class_table(const char* text, size_t bytes, ClassTable* out, ClassTableParseError* error) {
  if (error) *error = ClassTableParseError{};
  if (out == nullptr) return Status::InvalidArgument;
  out->clear();
  if (text == nullptr && bytes > 0) return Status::InvalidArgument;
  uint32_t line = 0;
  size_t pos = 0;
  while (pos < bytes) {
    ++line;
    if (line > kClassTableMaxLines) {
      out->clear();
      fail(error, line, 0, "more than 4096 lines");
      return Status::CapacityExceeded;
    }
    size_t end = pos;
    while (end < bytes && text[end] != '\n') ++end;
    if (end - pos > kClassTableMaxLineBytes) {
      out->clear();
      fail(error, line, 0, "line longer than 256 bytes");
      return Status::CapacityExceeded;
    }
    Status s;
    if (!parse_line(text + pos, static_cast<uint32_t>(end - pos), line, out, error, &s)) {
      out->clear();
      return s;
    }
    pos = end + 1;  // past the newline (or past the end)
  }
  if (out->size() == 0) {
    fail(error, 0, 0, "no entries");
    return Status::CorruptData;
  }
  return Status::Ok;
}

Status load_class_table(const std::string& path, ClassTable* out, ClassTableParseError* error) {
  if (error) *error = ClassTableParseError{};
  if (out == nullptr) return Status::InvalidArgument;
  out->clear();
  detail::InputFile f;
  const Status s = f.open(path.c_str());
  if (s != Status::Ok) {
    if (error) error->message = s == Status::NotFound ? "file not found" : "file cannot be opened";
    return s;
  }
  // Anything larger holds more than 4096 lines of at most 256 bytes (+ LF).
  constexpr uint64_t kMaxBytes = uint64_t(kClassTableMaxLines) * (kClassTableMaxLineBytes + 1);
  if (f.size() > kMaxBytes) {
    if (error) error->message = "file larger than 4096 lines of 256 bytes";
    return Status::CapacityExceeded;
  }
  std::vector<char> text(static_cast<size_t>(f.size()));
  if (!text.empty() && f.read_exact(text.data(), text.size()) != Status::Ok) {
    if (error) error->message = "read error";
    return Status::IoError;
  }
  return parse_class_table(text.data(), text.size(), out, error);
}

std::string format_class_table(const ClassTable& table) {
  std::string s = "# id name library_class stability role\n";
  char line[kClassTableMaxLineBytes + 64];
  for (uint32_t i = 0; i < table.size(); ++i) {
    const ClassTableEntry& e = table.entry(i);
    const bool ignored = e.library_class == kIgnoredClass;
    // The shortest fixed-point form that parses back to the same float, without the leading zero of a
    // weight below 1 so that 12 decimals fit parse_decimal's 12 digits (any weight parse_class_table
    // accepted was written with at most 12 digits, e.g. ".000040400407", found by fuzz_class_table).
    const float w = ignored ? 0.0f : table.stability(e.library_class);
    char num[32];
    const char* shortest = num;
    for (int p = 1; p <= 12; ++p) {
      std::snprintf(num, sizeof(num), "%.*f", p, double(w));
      shortest = (num[0] == '0' && num[1] == '.') ? num + 1 : num;
      float back = -1.0f;
      if (parse_decimal(Token{shortest, static_cast<uint32_t>(std::strlen(shortest))}, &back) && back == w) break;
    }
    std::snprintf(line, sizeof(line), "%u %s %s %s %s\n", unsigned(e.raw_id), e.name[0] ? e.name : "-",
                  ignored ? "ignored" : class_name(e.library_class), shortest, role_name(e.role));
    s += line;
  }
  return s;
}

}  // namespace gsf::port
