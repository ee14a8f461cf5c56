// C API: version, status names and the thread-local last-error message.
#include <cstdio>
#include <utility>

#include "capi/guard.h"
#include "volley/volley.h"

namespace volley::capi {
namespace {

/// Room for the longest message volley writes (a file-free, one-line description);
/// longer ones are cut.
constexpr std::size_t kMessageBytes = 512;

/// This thread's last error. A fixed buffer: recording an error never allocates, so
/// it cannot fail while an out-of-memory error is being reported.
thread_local char last_error[kMessageBytes] = "";

#define VOLLEY_STRINGIFY_(x) #x
#define VOLLEY_STRINGIFY(x) VOLLEY_STRINGIFY_(x)

}  // namespace

void fail(volley_status status, std::string message) { throw Failure{status, std::move(message)}; }

volley_status set_error(volley_status status, const char* function, const char* message) noexcept {
  std::snprintf(last_error, kMessageBytes, "%s: %s", function, message);
  return status;
}

}  // namespace volley::capi

extern "C" {

const char* volley_version(void) {
  return VOLLEY_STRINGIFY(VOLLEY_VERSION_MAJOR) "." VOLLEY_STRINGIFY(VOLLEY_VERSION_MINOR) "." VOLLEY_STRINGIFY(
      VOLLEY_VERSION_PATCH);
}

const char* volley_last_error(void) { return volley::capi::last_error; }

const char* volley_status_string(volley_status status) {
  switch (status) {
    case VOLLEY_OK: return "VOLLEY_OK";
    case VOLLEY_ERROR_INVALID_ARGUMENT: return "VOLLEY_ERROR_INVALID_ARGUMENT";
    case VOLLEY_ERROR_INVALID_GEOMETRY: return "VOLLEY_ERROR_INVALID_GEOMETRY";
    case VOLLEY_ERROR_MISALIGNED: return "VOLLEY_ERROR_MISALIGNED";
    case VOLLEY_ERROR_NOT_COMMITTED: return "VOLLEY_ERROR_NOT_COMMITTED";
    case VOLLEY_ERROR_UNSUPPORTED_ISA: return "VOLLEY_ERROR_UNSUPPORTED_ISA";
    case VOLLEY_ERROR_OUT_OF_MEMORY: return "VOLLEY_ERROR_OUT_OF_MEMORY";
    case VOLLEY_ERROR_INVALID_RAY: return "VOLLEY_ERROR_INVALID_RAY";
    case VOLLEY_ERROR_INTERNAL: return "VOLLEY_ERROR_INTERNAL";
    case VOLLEY_ERROR_FILE: return "VOLLEY_ERROR_FILE";
    case VOLLEY_ERROR_BUFFER_TOO_SMALL: return "VOLLEY_ERROR_BUFFER_TOO_SMALL";
  }
  return "unknown status";
}

}  // extern "C"
