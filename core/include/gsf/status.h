// Status codes returned by every fallible call in gsf. No exceptions anywhere in core/.
#pragma once
#include <cstdint>

namespace gsf {

// Negative-free enum so it can be stored in packed results and compared cheaply.
enum class Status : uint8_t {
  Ok = 0,
  InvalidArgument,   // a parameter or Config value is out of its documented range
  InvalidInput,      // scan data unusable (NaN/Inf, empty after gating, ...)
  CapacityExceeded,  // a fixed capacity from Config was hit; see each call for what was kept
  BufferTooSmall,    // caller buffer smaller than required_bytes(config)
  NotInitialized,    // call before a successful init()
  CorruptData,       // map/scan bytes failed a size, range or CRC check
  VersionMismatch,   // map written by an incompatible format version
  ConfigMismatch,    // map built with Config values the localizer cannot use
  Truncated,         // input shorter than its header says
  IoError,           // port layer: file missing, unreadable, short read
  NotFound,          // lookup miss (e.g. scan index past the end of a sequence)
  BudgetExhausted,   // a search budget ran out; the best result so far is returned
  NoSolution,        // localization produced no pose (too few instances / inliers)
  Unsupported,       // a feature not compiled in or not implemented for this input
};

// Human-readable name; never null, static storage.
const char* to_string(Status s);

inline bool ok(Status s) { return s == Status::Ok; }

}  // namespace gsf
