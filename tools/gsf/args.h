// Minimal, strict command-line parsing for the gsf CLI: --name value / --flag, unknown options and a
// value option given twice are errors.
#pragma once
#include <map>
#include <string>
#include <vector>

namespace gsf::cli {

struct OptionSpec {
  std::string name;  // without leading dashes
  std::string help;
  std::string default_value;  // empty and !is_flag -> required when `required` is set
  bool is_flag = false;
  bool required = false;
};

class Args {
 public:
  // Parses argv[first..argc); on error fills `error` and returns false.
  bool parse(int argc, char** argv, int first, const std::vector<OptionSpec>& specs, std::string* error);
  bool has(const std::string& name) const { return values_.count(name) > 0; }
  std::string get(const std::string& name) const;
  // Numeric getters fail (return false, set error) on malformed numbers.
  bool get_int(const std::string& name, long long* out, std::string* error) const;
  bool get_double(const std::string& name, double* out, std::string* error) const;
  // A comma list of min_count..max_count finite numbers ("512345,5412345" or "1,2,3") into out[0..];
  // *count (if given) is how many there were.
  bool get_doubles(const std::string& name, int min_count, int max_count, double* out, int* count,
                   std::string* error) const;
  bool flag(const std::string& name) const { return has(name) && values_.at(name) == "1"; }

 private:
  std::map<std::string, std::string> values_;
  std::map<std::string, std::string> defaults_;
};

std::string usage_text(const std::string& command, const std::string& summary, const std::vector<OptionSpec>& specs);

}  // namespace gsf::cli
