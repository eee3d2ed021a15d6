// An allocator that backs large arrays with 2 MB pages (transparent huge pages, asked for by
// madvise): the environment map's texels and alias table are read at random by every sample,
// 12 MB for a 1024 x 512 map, and with 4 KB pages nearly every such read also missed the TLB.
// Arrays under 2 MB, and systems that refuse, get ordinary pages.
#pragma once

#include <sys/mman.h>

#include <cstdlib>
#include <new>
#include <vector>

namespace freqlab {

template <class T>
struct HugePageAllocator {
    using value_type = T;
    static constexpr size_t kHugePage = size_t(1) << 21;

    HugePageAllocator() = default;
    template <class U>
    HugePageAllocator(const HugePageAllocator<U>&) {}

    static bool huge(size_t n) { return n * sizeof(T) >= kHugePage; }
    static size_t rounded(size_t n) {
        return (n * sizeof(T) + kHugePage - 1) / kHugePage * kHugePage;
    }

    T* allocate(size_t n) {
        if (!huge(n)) return static_cast<T*>(::operator new(n * sizeof(T)));
        void* p = std::aligned_alloc(kHugePage, rounded(n));
        if (!p) throw std::bad_alloc();
        madvise(p, rounded(n), MADV_HUGEPAGE);  // advice only: failure leaves 4 KB pages
        return static_cast<T*>(p);
    }
    void deallocate(T* p, size_t n) {
        if (huge(n))
            std::free(p);
        else
            ::operator delete(p);
    }
    template <class U>
    bool operator==(const HugePageAllocator<U>&) const {
        return true;
    }
    template <class U>
    bool operator!=(const HugePageAllocator<U>&) const {
        return false;
    }
};

template <class T>
using HugePageVector = std::vector<T, HugePageAllocator<T>>;

}  // namespace freqlab
