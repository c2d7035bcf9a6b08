// SPDX-License-Identifier: GPL-3.0-or-later
// Large blocks on transparent huge pages, for the two executables.
//
// Clouds, octrees and fields are arrays of tens to hundreds of megabytes that
// are filled right after they are allocated. With 4 KiB pages the kernel
// takes one fault per page on first touch; on the virtual machines this was
// measured on that costs 2.7 ms per MB (270 ms for 100 MB, more than the
// normals of a million points take), against 0.08 ms per MB on 2 MiB pages.
// The kernel's default (transparent_hugepage=madvise) only gives huge pages to
// regions marked MADV_HUGEPAGE, and glibc marks them only when its tunable
// glibc.malloc.hugetlb=1 is set in the environment before the process starts.
// So the global allocation function is replaced (a replacement the C++
// standard provides for): blocks of 4 MiB and more are aligned on 2 MiB and
// marked; smaller ones go to malloc as before. Everything is released with
// free(), which accepts both. Left out under the sanitizers, which replace
// these functions themselves.
#if defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer) || __has_feature(memory_sanitizer)
#define SCANDIFF_SANITIZED 1
#endif
#endif
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
#define SCANDIFF_SANITIZED 1
#endif

#if !defined(SCANDIFF_SANITIZED) && defined(__linux__)

#include <cstdlib>
#include <new>
#include <sys/mman.h>

namespace {

constexpr std::size_t kHugePage = std::size_t(2) << 20;
constexpr std::size_t kLargeBlock = std::size_t(4) << 20;

void* allocate(std::size_t size) noexcept
{
    if (size < kLargeBlock)
        return std::malloc(size == 0 ? 1 : size);
    void* block = nullptr;
    if (posix_memalign(&block, kHugePage, size) != 0)
        return nullptr;
    // Advice only: if the kernel has no huge page to give, 4 KiB pages serve.
    // Whole huge pages inside the block only: the memory after it is not ours.
    madvise(block, size & ~(kHugePage - 1), MADV_HUGEPAGE);
    return block;
}

//! The standard's loop: while there is no memory, call the new-handler (which
//! may free some) and try again; without one, bad_alloc.
void* allocateOrThrow(std::size_t size)
{
    for (;;) {
        if (void* block = allocate(size))
            return block;
        const std::new_handler handler = std::get_new_handler();
        if (!handler)
            throw std::bad_alloc();
        handler();
    }
}

} // namespace

void* operator new(std::size_t size)
{
    return allocateOrThrow(size);
}

void* operator new[](std::size_t size)
{
    return allocateOrThrow(size);
}

void* operator new(std::size_t size, const std::nothrow_t&) noexcept
{
    try {
        return allocateOrThrow(size);
    } catch (...) {
        return nullptr;
    }
}

void* operator new[](std::size_t size, const std::nothrow_t&) noexcept
{
    try {
        return allocateOrThrow(size);
    } catch (...) {
        return nullptr;
    }
}

void operator delete(void* block) noexcept
{
    std::free(block);
}

void operator delete[](void* block) noexcept
{
    std::free(block);
}

void operator delete(void* block, std::size_t) noexcept
{
    std::free(block);
}

void operator delete[](void* block, std::size_t) noexcept
{
    std::free(block);
}

#endif
