#include "args.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <sstream>

namespace gsf::cli {

bool Args::parse(int argc, char** argv, int first, const std::vector<OptionSpec>& specs, std::string* error) {
  for (const auto& s : specs)
    if (!s.is_flag && !s.default_value.empty()) defaults_[s.name] = s.default_value;
  for (int i = first; i < argc; ++i) {
    std::string a = argv[i];
    if (a.rfind("--", 0) != 0 || a.size() < 3) {
      *error = "unexpected argument '" + a + "'";
      return false;
    }
    std::string name = a.substr(2), value;
    const auto eq = name.find('=');
    bool has_inline = eq != std::string::npos;
    if (has_inline) {
      value = name.substr(eq + 1);
      name = name.substr(0, eq);
    }
    const OptionSpec* spec = nullptr;
    for (const auto& s : specs)
      if (s.name == name) spec = &s;
    if (!spec) {
      *error = "unknown option '--" + name + "'";
      return false;
    }
    if (spec->is_flag) {
      if (has_inline) {
        *error = "option '--" + name + "' takes no value";
        return false;
      }
      values_[name] = "1";
      continue;
    }
    if (!has_inline) {
      if (i + 1 >= argc) {
        *error = "option '--" + name + "' needs a value";
        return false;
      }
      value = argv[++i];
    }
    // A second value would silently replace the first (a second `--set` dropped the first list's
    // overrides in a benchmark once): strict, like an unknown option.
    if (values_.count(name)) {
      *error = "option '--" + name + "' given twice (--set takes one list: name=value,name=value)";
      return false;
    }
    values_[name] = value;
  }
  for (const auto& s : specs)
    if (s.required && !has(s.name)) {
      *error = "missing required option '--" + s.name + "'";
      return false;
    }
  return true;
}

std::string Args::get(const std::string& name) const {
  auto it = values_.find(name);
  if (it != values_.end()) return it->second;
  auto d = defaults_.find(name);
  return d == defaults_.end() ? std::string() : d->second;
}

bool Args::get_int(const std::string& name, long long* out, std::string* error) const {
  const std::string v = get(name);
  char* end = nullptr;
  errno = 0;
  long long x = std::strtoll(v.c_str(), &end, 10);
  if (v.empty() || errno != 0 || *end != '\0') {
    *error = "option '--" + name + "' expects an integer, got '" + v + "'";
    return false;
  }
  *out = x;
  return true;
}

bool Args::get_double(const std::string& name, double* out, std::string* error) const {
  const std::string v = get(name);
  char* end = nullptr;
  errno = 0;
  double x = std::strtod(v.c_str(), &end);
  if (v.empty() || errno != 0 || *end != '\0') {
    *error = "option '--" + name + "' expects a number, got '" + v + "'";
    return false;
  }
  *out = x;
  return true;
}

bool Args::get_doubles(const std::string& name, int min_count, int max_count, double* out, int* count,
                       std::string* error) const {
  const std::string v = get(name);
  int n = 0;
  size_t pos = 0;
  while (true) {
    const size_t comma = v.find(',', pos);
    const std::string item = v.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    char* end = nullptr;
    errno = 0;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || errno != 0 || *end != '\0' || !std::isfinite(x) || n >= max_count) {
      *error = "option '--" + name + "' expects " + std::to_string(min_count) + " to " + std::to_string(max_count) +
               " comma-separated numbers, got '" + v + "'";
      return false;
    }
    out[n++] = x;
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  if (n < min_count) {
    *error = "option '--" + name + "' expects " + std::to_string(min_count) + " to " + std::to_string(max_count) +
             " comma-separated numbers, got '" + v + "'";
    return false;
  }
  if (count) *count = n;
  return true;
}

std::string usage_text(const std::string& command, const std::string& summary, const std::vector<OptionSpec>& specs) {
  std::ostringstream o;
  o << "usage: gsf " << command;
  for (const auto& s : specs)
    if (s.required) o << " --" << s.name << " " << (s.is_flag ? "" : "VALUE");
  o << " [options]\n\n" << summary << "\n\noptions:\n";
  for (const auto& s : specs) {
    std::string lhs = "  --" + s.name + (s.is_flag ? "" : " VALUE");
    if (lhs.size() < 26) lhs.resize(26, ' ');
    o << lhs << " " << s.help;
    if (!s.default_value.empty()) o << " (default: " << s.default_value << ")";
    if (s.required) o << " [required]";
    o << "\n";
  }
  return o.str();
}

}  // namespace gsf::cli
