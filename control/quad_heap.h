// A min-priority queue of (key, id) pairs as a 4-ary heap (issue 15): the
// planner's open list. The elements come off in the order of the pairs
// themselves (key, then id, as std::pair compares them), which is a total
// order, so the sequence of pops is exactly std::priority_queue's with
// std::greater (equal pairs are indistinguishable). Four children per node
// halve the heap's depth and keep a node's children in one or two cache lines,
// so a pop costs fewer cache misses than in a binary heap (D. B. Johnson,
// "Priority queues with update and finding minimum spanning trees", Inf.
// Process. Lett. 4(3), 1975: d-ary heaps; LaMarca & Ladner, "The influence of
// caches on the performance of heaps", JEA 1, 1996: 4-ary fastest in practice).
// Pure.
#ifndef IRSLAM_CONTROL_QUAD_HEAP_H_
#define IRSLAM_CONTROL_QUAD_HEAP_H_

#include <cstddef>
#include <utility>
#include <vector>

namespace irslam::control {

class QuadHeap {
 public:
  using Entry = std::pair<double, int>;

  bool empty() const { return a_.empty(); }
  size_t size() const { return a_.size(); }
  void clear() { a_.clear(); }

  void push(Entry e) {
    size_t k = a_.size();
    a_.push_back(e);
    while (k > 0) {
      const size_t parent = (k - 1) / 4;
      if (!(e < a_[parent])) break;
      a_[k] = a_[parent];
      k = parent;
    }
    a_[k] = e;
  }

  // The least pair, removed. Not on an empty heap.
  Entry pop() {
    const Entry top = a_.front();
    const Entry last = a_.back();
    a_.pop_back();
    const size_t n = a_.size();
    if (n == 0) return top;
    size_t k = 0;
    for (;;) {
      const size_t first = 4 * k + 1;
      if (first >= n) break;
      size_t best = first;
      const size_t end = first + 4 < n ? first + 4 : n;
      for (size_t c = first + 1; c < end; ++c) {
        if (a_[c] < a_[best]) best = c;
      }
      if (!(a_[best] < last)) break;
      a_[k] = a_[best];
      k = best;
    }
    a_[k] = last;
    return top;
  }

 private:
  std::vector<Entry> a_;
};

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_QUAD_HEAP_H_
