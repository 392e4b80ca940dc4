// Binary min-heap whose elements carry their own position, so a key change
// is an O(log n) sift instead of a search or a duplicate entry.
#pragma once

#include <cstddef>
#include <utility>
#include <vector>

namespace plr::search {

struct HeapElement {
  // Position in the heap + 1; 0 when not in a heap.
  std::size_t heap_slot = 0;
  double key = 0.0;
  double tie = 0.0;  // second key: smaller first among equal keys
};

template <class T>  // T derives from HeapElement
class IntrusiveHeap {
 public:
  bool empty() const { return items_.empty(); }
  std::size_t size() const { return items_.size(); }
  bool contains(const T* e) const { return e->heap_slot != 0; }
  T* top() const { return items_.front(); }
  double top_key() const { return items_.front()->key; }

  void push(T* e) {
    items_.push_back(e);
    e->heap_slot = items_.size();
    up(items_.size() - 1);
  }
  // After changing e's key (either direction).
  void update(T* e) {
    const std::size_t i = e->heap_slot - 1;
    up(i);
    down(e->heap_slot - 1);
  }
  void push_or_update(T* e) {
    if (contains(e)) {
      update(e);
    } else {
      push(e);
    }
  }
  T* pop() {
    T* e = items_.front();
    swap_at(0, items_.size() - 1);
    items_.pop_back();
    e->heap_slot = 0;
    if (!items_.empty()) down(0);
    return e;
  }
  void clear() {
    for (T* e : items_) e->heap_slot = 0;
    items_.clear();
  }
  // Every element, in heap order (for re-keying).
  const std::vector<T*>& items() const { return items_; }
  // Restores the heap after keys changed en masse.
  void rebuild() {
    for (std::size_t i = items_.size() / 2; i-- > 0;) down(i);
  }

 private:
  static bool less(const T* a, const T* b) {
    return a->key < b->key || (a->key == b->key && a->tie < b->tie);
  }
  void swap_at(std::size_t i, std::size_t j) {
    std::swap(items_[i], items_[j]);
    items_[i]->heap_slot = i + 1;
    items_[j]->heap_slot = j + 1;
  }
  void up(std::size_t i) {
    while (i > 0) {
      const std::size_t p = (i - 1) / 2;
      if (!less(items_[i], items_[p])) break;
      swap_at(i, p);
      i = p;
    }
  }
  void down(std::size_t i) {
    for (;;) {
      const std::size_t l = 2 * i + 1, r = l + 1;
      std::size_t m = i;
      if (l < items_.size() && less(items_[l], items_[m])) m = l;
      if (r < items_.size() && less(items_[r], items_[m])) m = r;
      if (m == i) return;
      swap_at(i, m);
      i = m;
    }
  }

  std::vector<T*> items_;
};

}  // namespace plr::search
