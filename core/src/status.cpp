#include "gsf/status.h"

namespace gsf {

const char* to_string(Status s) {
  switch (s) {
    case Status::Ok: return "Ok";
    case Status::InvalidArgument: return "InvalidArgument";
    case Status::InvalidInput: return "InvalidInput";
    case Status::CapacityExceeded: return "CapacityExceeded";
    case Status::BufferTooSmall: return "BufferTooSmall";
    case Status::NotInitialized: return "NotInitialized";
    case Status::CorruptData: return "CorruptData";
    case Status::VersionMismatch: return "VersionMismatch";
    case Status::ConfigMismatch: return "ConfigMismatch";
    case Status::Truncated: return "Truncated";
    case Status::IoError: return "IoError";
    case Status::NotFound: return "NotFound";
    case Status::BudgetExhausted: return "BudgetExhausted";
    case Status::NoSolution: return "NoSolution";
    case Status::Unsupported: return "Unsupported";
  }
  return "Unknown";
}

}  // namespace gsf
