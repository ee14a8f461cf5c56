// The C API's error boundary: every exported function runs its body in guarded(), which
// turns any C++ exception into a volley_status and a thread-local message. Nothing is
// thrown across the C boundary.
#pragma once
#include <new>
#include <string>
#include <utility>

#include "volley/accel.h"
#include "volley/volley.h"

namespace volley::capi {

/// An error detected at the boundary: the status to return and the message (without the
/// function name, which guarded() prepends).
struct Failure {
  volley_status status;
  std::string message;
};

/// Throws Failure{status, message}.
[[noreturn]] void fail(volley_status status, std::string message);

/// Stores "`function`: `message`" as this thread's last error (truncated to the buffer;
/// never allocates, never throws) and returns `status`.
volley_status set_error(volley_status status, const char* function, const char* message) noexcept;

/// Runs body() and returns VOLLEY_OK, or the status of the exception it threw:
/// Failure -> its status; std::bad_alloc and volley::OutOfMemory ->
/// VOLLEY_ERROR_OUT_OF_MEMORY; volley::Error
/// (input the C++ layer rejected) -> `error_status`; anything else -> VOLLEY_ERROR_INTERNAL.
template <class Body>
volley_status guarded(const char* function, volley_status error_status, Body&& body) noexcept {
  try {
    std::forward<Body>(body)();
    return VOLLEY_OK;
  } catch (const Failure& f) {
    return set_error(f.status, function, f.message.c_str());
  } catch (const std::bad_alloc&) {
    return set_error(VOLLEY_ERROR_OUT_OF_MEMORY, function, "out of memory");
  } catch (const OutOfMemory& e) {
    return set_error(VOLLEY_ERROR_OUT_OF_MEMORY, function, e.what());
  } catch (const Error& e) {
    return set_error(error_status, function, e.what());
  } catch (const std::exception& e) {
    return set_error(VOLLEY_ERROR_INTERNAL, function, e.what());
  } catch (...) {
    return set_error(VOLLEY_ERROR_INTERNAL, function, "unknown exception");
  }
}

/// Fails with VOLLEY_ERROR_INVALID_ARGUMENT ("`name` is NULL") when p is null.
inline void require_pointer(const void* p, const char* name) {
  if (p == nullptr) fail(VOLLEY_ERROR_INVALID_ARGUMENT, std::string(name) + " is NULL");
}

}  // namespace volley::capi
