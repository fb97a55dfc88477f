#pragma once
// Lock-free hand-over between the real-time loop and the other threads of the robot service.

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <type_traits>

namespace concert::hardware {

/// Triple buffer: one writer hands the latest value of T to one reader without either ever
/// waiting for the other (no mutex, no allocation: the three T are made up front, so T's
/// vectors must already have their final sizes). The writer fills back() and publish()es it;
/// the reader calls update() and then reads front(), which stays untouched by the writer
/// until the reader's next update(). Values published between two updates collapse to the
/// newest (latest-value semantics: accumulate in the writer if nothing may be lost).
template <class T> class RealtimeBuffer {
 public:
  explicit RealtimeBuffer(const T& initial = T{}) : buffers_{initial, initial, initial} {}
  /// Each of the three values made by `make()` (a copy would drop reserved capacity).
  template <class Make, class = std::enable_if_t<std::is_invocable_r_v<T, Make>>>
  explicit RealtimeBuffer(Make make) : buffers_{make(), make(), make()} {}
  RealtimeBuffer(const RealtimeBuffer&) = delete;
  RealtimeBuffer& operator=(const RealtimeBuffer&) = delete;

  /// Writer side: the buffer to fill (its content is some older value).
  T& back() { return buffers_[back_]; }
  /// Writer side: makes back() the newest value.
  void publish() { back_ = middle_.exchange(back_ | kFresh, std::memory_order_acq_rel) & kIndex; }

  /// Reader side: takes the newest published value if there is one; true if front() changed.
  bool update() {
    if ((middle_.load(std::memory_order_acquire) & kFresh) == 0) {
      return false;
    }
    front_ = middle_.exchange(front_, std::memory_order_acq_rel) & kIndex;
    return true;
  }
  /// Reader side: the value taken by the last update().
  const T& front() const { return buffers_[front_]; }

 private:
  static constexpr int kIndex = 3;
  static constexpr int kFresh = 4;
  std::array<T, 3> buffers_;
  int back_{0};
  int front_{1};
  std::atomic<int> middle_{2};
};

/// Single-producer single-consumer hand-over of owned objects from a non-real-time thread to
/// the loop and back: submit() offers a prepared object (replacing one the loop did not
/// take yet, which is then deleted by the submitter); the loop take()s it at a cycle
/// boundary and retire()s the one it replaces; the objects the loop gave back are deleted
/// by the next submit() or collect() on the non-real-time side, never on the loop thread.
template <class T> class Handover {
 public:
  Handover() = default;
  Handover(const Handover&) = delete;
  Handover& operator=(const Handover&) = delete;
  ~Handover() {
    delete pending_.exchange(nullptr);
    collect();
  }

  /// Non-real-time side: offers `object` to the loop.
  void submit(std::unique_ptr<T> object) {
    collect();
    std::unique_ptr<T> replaced(pending_.exchange(object.release(), std::memory_order_acq_rel));
  }
  /// Non-real-time side: deletes what the loop retired.
  void collect() {
    for (auto& slot : retired_) {
      std::unique_ptr<T> done(slot.exchange(nullptr, std::memory_order_acq_rel));
    }
  }
  /// True if an offered object waits for the loop.
  [[nodiscard]] bool pending() const { return pending_.load(std::memory_order_acquire) != nullptr; }

  /// Loop side: the offered object, or null. The loop owns it until it retires it.
  T* take() { return pending_.exchange(nullptr, std::memory_order_acq_rel); }
  /// Loop side: gives an object back for deletion off the loop thread. Returns false (the
  /// caller keeps it) if every retire slot is still full.
  bool retire(T* object) {
    if (object == nullptr) {
      return true;
    }
    for (auto& slot : retired_) {
      T* expected = nullptr;
      if (slot.compare_exchange_strong(expected, object, std::memory_order_acq_rel)) {
        return true;
      }
    }
    return false;
  }

 private:
  std::atomic<T*> pending_{nullptr};
  std::array<std::atomic<T*>, 4> retired_{};
};

}  // namespace concert::hardware
