// Tiny streaming JSON writer (objects, arrays, numbers, strings) for machine-readable CLI output.
#pragma once
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace gsf::cli {

class JsonWriter {
 public:
  std::string str() const { return out_; }
  void begin_object() {
    value_prefix();
    out_ += '{';
    stack_.push_back(true);
  }
  void end_object() {
    out_ += '}';
    stack_.pop_back();
  }
  void begin_array() {
    value_prefix();
    out_ += '[';
    stack_.push_back(true);
  }
  void end_array() {
    out_ += ']';
    stack_.pop_back();
  }
  void key(const std::string& k) {
    if (!stack_.back()) out_ += ',';
    stack_.back() = false;
    escape(k);
    out_ += ':';
    after_key_ = true;
  }
  void value(const std::string& s) {
    value_prefix();
    escape(s);
  }
  void value(const char* s) { value(std::string(s)); }
  void value(bool b) {
    value_prefix();
    out_ += b ? "true" : "false";
  }
  void value(double d) {
    value_prefix();
    if (!std::isfinite(d)) {
      out_ += "null";
      return;
    }
    char buf[40];
    std::snprintf(buf, sizeof(buf), "%.9g", d);
    out_ += buf;
  }
  // A double with every digit (%.17g: round-trips exactly), for map-frame coordinates such as UTM
  // northings, where value()'s 9 significant digits would keep only centimetres.
  void exact(double d) {
    value_prefix();
    if (!std::isfinite(d)) {
      out_ += "null";
      return;
    }
    char buf[40];
    std::snprintf(buf, sizeof(buf), "%.17g", d);
    out_ += buf;
  }
  void value(long long v) {
    value_prefix();
    out_ += std::to_string(v);
  }
  void value(unsigned long long v) {
    value_prefix();
    out_ += std::to_string(v);
  }
  void value(int v) { value(static_cast<long long>(v)); }
  void value(unsigned v) { value(static_cast<unsigned long long>(v)); }
  void value(unsigned long v) { value(static_cast<unsigned long long>(v)); }
  void value(long v) { value(static_cast<long long>(v)); }
  void value(float v) { value(static_cast<double>(v)); }
  template <class T>
  void field(const std::string& k, const T& v) {
    key(k);
    value(v);
  }

 private:
  void value_prefix() {
    if (after_key_) {
      after_key_ = false;
      return;
    }
    if (!stack_.empty()) {
      if (!stack_.back()) out_ += ',';
      stack_.back() = false;
    }
  }
  void escape(const std::string& s) {
    out_ += '"';
    for (char c : s) {
      switch (c) {
        case '"': out_ += "\\\""; break;
        case '\\': out_ += "\\\\"; break;
        case '\n': out_ += "\\n"; break;
        case '\t': out_ += "\\t"; break;
        default:
          if (static_cast<unsigned char>(c) < 0x20) {
            char b[8];
            std::snprintf(b, sizeof(b), "\\u%04x", c);
            out_ += b;
          } else {
            out_ += c;
          }
      }
    }
    out_ += '"';
  }
  std::string out_;
  std::vector<bool> stack_;  // per open container: "next element is the first"
  bool after_key_ = false;
};

}  // namespace gsf::cli
