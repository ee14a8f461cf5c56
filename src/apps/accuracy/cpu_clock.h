// CPU time of the calling thread: the timed passes run on one thread, and on a shared,
// loaded machine its CPU time varies far less than wall time (as in perf/run).
#pragma once
#include <ctime>

namespace volley::accuracy {

/// Seconds of CPU time this thread has used (CLOCK_THREAD_CPUTIME_ID).
inline double thread_cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

}  // namespace volley::accuracy
