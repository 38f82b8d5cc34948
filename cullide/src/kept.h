// kept.h (private): storage a function keeps per calling thread from one call to the next.
//
// The exact stage makes buffers of megabytes every frame (the triangle boxes, the gathered
// references). Freed at the end of a frame and allocated again at the start of the next, glibc may
// give their pages back to the kernel in between (when the free space at the top of its heap passes
// its trim threshold, which depends on what else was freed before), and then every page is faulted
// in and zeroed again: about 600 faults a call on the folded cloth's `exact --self`, in some runs
// and not in others, 1.2x the frame's time. Kept storage keeps its pages: each thread holds at most
// the largest buffer it needed, for the thread's lifetime.
//
// One user at a time per thread and tag. A oneTBB thread that waits inside a parallel loop may take
// another task, which may call the same function again on the same thread: that nested use gets a
// buffer of its own for the call, so the two never share. Nothing is kept but capacity: every user
// sets what it reads.
#pragma once

#include <cstddef>
#include <memory>
#include <optional>

namespace cullide::detail {

template <class V, class Tag>
class Kept {
   public:
    Kept() {
        Slot& s = slot();
        if (!s.busy) {
            s.busy = true;
            v_ = &s.value;
        } else {
            own_.emplace();
            v_ = &*own_;
        }
    }
    ~Kept() {
        if (!own_) slot().busy = false;
    }
    Kept(const Kept&) = delete;
    Kept& operator=(const Kept&) = delete;

    V& operator*() const { return *v_; }
    V* operator->() const { return v_; }

   private:
    struct Slot {
        V value{};
        bool busy = false;
    };
    static Slot& slot() {
        thread_local Slot s;
        return s;
    }
    std::optional<V> own_;
    V* v_ = nullptr;
};

// Raw bytes that only grow (by at least a quarter, so that slowly growing frames do not reallocate
// every time), aligned for any type up to the default new alignment.
class KeptBytes {
   public:
    std::byte* reserve(std::size_t bytes) {
        if (bytes > size_) {
            const std::size_t grown = size_ + size_ / 4;
            const std::size_t size = bytes > grown ? bytes : grown;
            data_.reset();  // (the old buffer goes first: never both at once)
            size_ = 0;
            data_.reset(new std::byte[size]);
            size_ = size;
        }
        return data_.get();
    }

   private:
    std::unique_ptr<std::byte[]> data_;
    std::size_t size_ = 0;
};

}  // namespace cullide::detail
