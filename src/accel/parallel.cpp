// accel::arena_of: the oneTBB arenas the batch forms run on, one per calling thread and thread count.
#include "accel/parallel.h"

#include <map>
#include <memory>

namespace volley::accel {

tbb::task_arena& arena_of(int threads) {
  thread_local std::map<int, std::unique_ptr<tbb::task_arena>> arenas;
  std::unique_ptr<tbb::task_arena>& arena = arenas[threads];
  if (!arena) arena = std::make_unique<tbb::task_arena>(threads);
  return *arena;
}

}  // namespace volley::accel
