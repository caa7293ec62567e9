// Exact engine (docs/model.md §2, §2.1, §4.2, §7, §8): the double instantiation. The quad one is in
// dynamics/simulate_quad.cpp.
#include "dynamics/exact_engine.hpp"

namespace vibro::detail {

long long& ThreadProbeCount() {
  thread_local long long count = 0;
  return count;
}

template class ExactEngineT<double>;

}  // namespace vibro::detail
