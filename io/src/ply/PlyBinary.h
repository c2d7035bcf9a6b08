// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The PLY reader's binary passes: values loaded in either byte order,
//! fixed-size records visited by chunks on both cores, records of variable
//! size in file order, elements skipped, faces read. Templates on the byte
//! order, so that the per-value loops are compiled for each.

#include "ply/PlyLayout.h"

#include "internal/MappedFile.h"

#include <scandiff/core/Progress.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstring>
#include <optional>

namespace scandiff::io::detail::ply {

template <typename T, bool Swap>
inline T load(const char* p)
{
    T value;
    if constexpr (!Swap) {
        std::memcpy(&value, p, sizeof(T));
    } else {
        char bytes[sizeof(T)];
        for (std::size_t i = 0; i < sizeof(T); ++i)
            bytes[i] = p[sizeof(T) - 1 - i];
        std::memcpy(&value, bytes, sizeof(T));
    }
    return value;
}

template <bool Swap>
inline double loadDouble(const char* p, PlyType type)
{
    switch (type) {
    case PlyType::Int8: return load<std::int8_t, Swap>(p);
    case PlyType::UInt8: return load<std::uint8_t, Swap>(p);
    case PlyType::Int16: return load<std::int16_t, Swap>(p);
    case PlyType::UInt16: return load<std::uint16_t, Swap>(p);
    case PlyType::Int32: return load<std::int32_t, Swap>(p);
    case PlyType::UInt32: return load<std::uint32_t, Swap>(p);
    case PlyType::Float32: return load<float, Swap>(p);
    case PlyType::Float64: return load<double, Swap>(p);
    }
    return 0.0;
}

//! Integer value of a list count or index; floating-point indices (seen in the
//! wild) are truncated, NaN maps to -1 so that it is rejected as out of range.
template <bool Swap>
inline std::int64_t loadInteger(const char* p, PlyType type)
{
    switch (type) {
    case PlyType::Int8: return load<std::int8_t, Swap>(p);
    case PlyType::UInt8: return load<std::uint8_t, Swap>(p);
    case PlyType::Int16: return load<std::int16_t, Swap>(p);
    case PlyType::UInt16: return load<std::uint16_t, Swap>(p);
    case PlyType::Int32: return load<std::int32_t, Swap>(p);
    case PlyType::UInt32: return load<std::uint32_t, Swap>(p);
    case PlyType::Float32:
    case PlyType::Float64: {
        const double v = loadDouble<Swap>(p, type);
        return (v >= 0.0 && v < 9e18) ? static_cast<std::int64_t>(v) : -1;
    }
    }
    return -1;
}

template <bool Swap>
const char* skipBinaryList(const PlyElement& e, const PlyProperty& p, std::uint64_t record, const char* ptr,
                           const char* end, const Context& ctx)
{
    const std::size_t countSize = typeSize(p.countType);
    if (static_cast<std::size_t>(end - ptr) < countSize)
        ctx.truncated(e, record);
    const std::int64_t count = loadInteger<Swap>(ptr, p.countType);
    if (count < 0)
        ctx.fail(e.name + " " + std::to_string(record + 1) + ": negative length " + std::to_string(count) +
                 " for list '" + p.name + "'");
    ptr += countSize;
    const std::size_t itemSize = typeSize(p.type);
    if (static_cast<std::uint64_t>(end - ptr) / itemSize < static_cast<std::uint64_t>(count))
        ctx.truncated(e, record);
    return ptr + static_cast<std::size_t>(count) * itemSize;
}

//! Calls visit(i, record) for each record of an element of fixed-size
//! records, after checking the file holds them all; returns the end of the
//! records. Records are visited in chunks on both cores, from one thread per
//! chunk, so the visitor must only write what belongs to record i (or to its
//! chunk, i / kChunk); each chunk's pages are released once read.
template <class Visit>
const char* visitFixedRecords(const PlyElement& e, const char* ptr, const char* end, const Context& ctx,
                              ProgressTicker& ticker, Visit&& visit)
{
    const std::uint64_t n = e.count;
    const std::size_t recordSize = e.minRecordSize();
    const std::uint64_t available = static_cast<std::uint64_t>(end - ptr) / recordSize;
    if (available < n)
        ctx.truncated(e, available);
    const std::uint64_t chunks = (n + kChunk - 1) / kChunk;
    tbb::parallel_for(tbb::blocked_range<std::uint64_t>(0, chunks, 1), [&](const tbb::blocked_range<std::uint64_t>& range) {
        for (std::uint64_t chunk = range.begin(); chunk != range.end(); ++chunk) {
            const std::uint64_t start = chunk * kChunk, stop = std::min(n, start + kChunk);
            const char* record = ptr + start * recordSize;
            const char* chunkBegin = record;
            for (std::uint64_t i = start; i < stop; ++i, record += recordSize)
                visit(i, record);
            MappedFile::releaseConsumed(chunkBegin, record);
            ticker.step(stop - start);
        }
    });
    return ptr + n * recordSize;
}

//! Calls visit(index, slot, value) for every used vertex property: in file
//! order for records of variable size, by chunks on several threads for
//! fixed-size records (see below).
template <bool Swap, class Visit>
const char* visitBinaryVertices(const PlyElement& e, const VertexLayout& layout, const char* ptr, const char* end,
                                const Context& ctx, ProgressTicker& ticker, Visit&& visit)
{
    const std::uint64_t n = e.count;
    if (e.fixedSize()) {
        const Slot* slotsBegin = layout.slots.data();
        const Slot* slotsEnd = slotsBegin + layout.slots.size();
        return visitFixedRecords(e, ptr, end, ctx, ticker, [&](std::uint64_t i, const char* record) {
            for (const Slot* s = slotsBegin; s != slotsEnd; ++s)
                visit(i, *s, loadDouble<Swap>(record + s->offset, s->type));
        });
    }
    for (std::uint64_t i = 0; i < n; ++i) {
        for (std::size_t j = 0; j < e.properties.size(); ++j) {
            const PlyProperty& p = e.properties[j];
            if (p.isList) {
                ptr = skipBinaryList<Swap>(e, p, i, ptr, end, ctx);
                continue;
            }
            const std::size_t size = typeSize(p.type);
            if (static_cast<std::size_t>(end - ptr) < size)
                ctx.truncated(e, i);
            if (const int slot = layout.slotOfProperty[j]; slot >= 0)
                visit(i, layout.slots[static_cast<std::size_t>(slot)], loadDouble<Swap>(ptr, p.type));
            ptr += size;
        }
        if ((i + 1) % kChunk == 0)
            ticker.step(kChunk);
    }
    ticker.step(n % kChunk);
    return ptr;
}

//! Where a record's x, y and z lie when they are three values of one
//! floating type: the layout every common writer uses (scandiff, CloudCompare,
//! PDAL). Coordinates-only passes (the box, a geometry-only read) then load
//! them directly instead of dispatching on every value's type and role.
struct PlainCoordinates
{
    PlyType type = PlyType::Float32;
    std::size_t offset[3] = {0, 0, 0};
};

//! The plain coordinates of `e`'s records, where they can be loaded
//! directly: fixed-size records in the machine's byte order.
template <bool Swap>
std::optional<PlainCoordinates> plainCoordinates(const VertexLayout& layout, const PlyElement& e)
{
    if (Swap || !e.fixedSize())
        return std::nullopt;
    PlainCoordinates plain;
    int found = 0;
    for (const Slot& s : layout.slots)
        if (s.role >= Role::X && s.role <= Role::Z) {
            if (found > 0 && s.type != plain.type)
                return std::nullopt;
            plain.type = s.type;
            plain.offset[static_cast<int>(s.role) - static_cast<int>(Role::X)] = s.offset;
            ++found;
        }
    if (found != 3 || (plain.type != PlyType::Float32 && plain.type != PlyType::Float64))
        return std::nullopt;
    return plain;
}

//! Calls visit(i, x, y, z) for every record of a fixed-size element in
//! native byte order whose coordinates are plain (see visitFixedRecords).
template <class Visit>
const char* visitPlainCoordinates(const PlyElement& e, const PlainCoordinates& plain, const char* ptr, const char* end,
                                  const Context& ctx, ProgressTicker& ticker, Visit&& visit)
{
    const std::size_t ox = plain.offset[0], oy = plain.offset[1], oz = plain.offset[2];
    const auto visitAs = [&](auto type) {
        using T = decltype(type);
        return visitFixedRecords(e, ptr, end, ctx, ticker, [&](std::uint64_t i, const char* record) {
            T x, y, z;
            std::memcpy(&x, record + ox, sizeof x);
            std::memcpy(&y, record + oy, sizeof y);
            std::memcpy(&z, record + oz, sizeof z);
            visit(i, static_cast<double>(x), static_cast<double>(y), static_cast<double>(z));
        });
    };
    return plain.type == PlyType::Float64 ? visitAs(double()) : visitAs(float());
}

template <bool Swap>
const char* skipBinaryElement(const PlyElement& e, const char* ptr, const char* end, const Context& ctx)
{
    if (e.fixedSize()) {
        const std::size_t recordSize = e.minRecordSize();
        if (recordSize == 0)
            return ptr;
        const std::uint64_t available = static_cast<std::uint64_t>(end - ptr) / recordSize;
        if (available < e.count)
            ctx.truncated(e, available);
        return ptr + e.count * recordSize;
    }
    for (std::uint64_t i = 0; i < e.count; ++i)
        for (const PlyProperty& p : e.properties) {
            if (p.isList) {
                ptr = skipBinaryList<Swap>(e, p, i, ptr, end, ctx);
            } else {
                const std::size_t size = typeSize(p.type);
                if (static_cast<std::size_t>(end - ptr) < size)
                    ctx.truncated(e, i);
                ptr += size;
            }
        }
    return ptr;
}

template <bool Swap>
const char* readBinaryFaces(const PlyElement& e, std::size_t indexProperty, FaceBuilder& builder, const char* ptr,
                            const char* end, const Context& ctx, ProgressTicker& ticker)
{
    for (std::uint64_t i = 0; i < e.count; ++i) {
        for (std::size_t j = 0; j < e.properties.size(); ++j) {
            const PlyProperty& p = e.properties[j];
            if (!p.isList) {
                const std::size_t size = typeSize(p.type);
                if (static_cast<std::size_t>(end - ptr) < size)
                    ctx.truncated(e, i);
                ptr += size;
                continue;
            }
            const char* next = skipBinaryList<Swap>(e, p, i, ptr, end, ctx);
            const char* items = ptr + typeSize(p.countType);
            if (j == indexProperty) {
                builder.begin(i);
                const std::size_t itemSize = typeSize(p.type);
                for (const char* item = items; item < next; item += itemSize)
                    builder.add(loadInteger<Swap>(item, p.type));
            }
            ptr = next;
        }
        if ((i + 1) % kChunk == 0)
            ticker.step(kChunk);
    }
    ticker.step(e.count % kChunk);
    return ptr;
}
} // namespace scandiff::io::detail::ply
