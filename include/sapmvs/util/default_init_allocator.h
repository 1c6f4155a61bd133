#pragma once
// An allocator whose value-less construction leaves a trivial element
// uninitialized, so that std::vector<T, DefaultInitAllocator<T>>(n) allocates
// without writing.
//
// A large array is mapped fresh (MemoryUse), and the first write to each of
// its pages faults. std::vector<int>(n) makes those writes on one thread, to
// fill it with zeros a parallel loop then overwrites: in the filter's
// neighbour table on the simulator's `city`, the fill alone was the main
// thread's largest serial step, with the other core idle. With this
// allocator the threads that compute the values take the faults.
#include <memory>
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

namespace sapmvs {

template <typename T, typename Base = std::allocator<T>>
class DefaultInitAllocator : public Base {
  using Traits = std::allocator_traits<Base>;

 public:
  template <typename U>
  struct rebind {
    using other = DefaultInitAllocator<U, typename Traits::template rebind_alloc<U>>;
  };

  using Base::Base;

  template <typename U>
  void construct(U* p) noexcept(std::is_nothrow_default_constructible_v<U>) {
    ::new (static_cast<void*>(p)) U;
  }
  template <typename U, typename... Args>
  void construct(U* p, Args&&... args) {
    Traits::construct(static_cast<Base&>(*this), p, std::forward<Args>(args)...);
  }
};

// A vector whose elements start uninitialized when T is trivial: every
// element must be written before it is read.
template <typename T>
using UninitializedVector = std::vector<T, DefaultInitAllocator<T>>;

}  // namespace sapmvs
