// SPDX-License-Identifier: GPL-3.0-or-later
//! LAZ writing: LAS 1.4 records compressed in LASzip's layered chunks (each
//! chunk: its first record as is, its point count, the byte count of every
//! layer, the layers), the chunk table after them, as LASzip's
//! laswritepoint.cpp lays them out. The item encoders are in laz/.

#include "laz/LazEncoder.h"
#include "laz/Items.h"

#include <scandiff/core/Error.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstring>

namespace scandiff::io::detail {

namespace {

constexpr std::uint32_t kChunkSize = 50000; //!< LASzip's default
//! Chunks compressed together (in parallel) before they are written.
constexpr std::size_t kChunksPerBatch = 8;

template <typename T>
void put(std::string& s, T value)
{
    char bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    s.append(bytes, sizeof(T));
}

//! One chunk of `count` records, compressed.
std::vector<unsigned char> compressChunk(const LazLayout& layout, const unsigned char* records, std::size_t count,
                                         std::size_t recordLength)
{
    std::vector<unsigned char> out(records, records + recordLength);
    std::uint32_t context = 0;
    std::vector<std::unique_ptr<laz::LayeredItemEncoder>> items;
    std::vector<std::size_t> offsets;
    std::size_t at = 0;
    for (const LazItem& item : layout.items) {
        items.push_back(laz::makeLayeredItemEncoder(item.type, item.size, records + at, context));
        offsets.push_back(at);
        at += item.size;
    }
    for (std::size_t p = 1; p < count; ++p) {
        // As in LASzip: each point starts from context 0, and the point14
        // item sets its channel only where the channel changes (laz/Items.h).
        context = 0;
        for (std::size_t i = 0; i < items.size(); ++i)
            items[i]->encode(records + p * recordLength + offsets[i], context);
    }
    std::vector<std::vector<unsigned char>> layers;
    for (auto& item : items)
        item->finish(layers);
    auto put32 = [&](std::uint32_t v) {
        unsigned char bytes[4];
        std::memcpy(bytes, &v, 4);
        out.insert(out.end(), bytes, bytes + 4);
    };
    put32(static_cast<std::uint32_t>(count));
    for (const auto& layer : layers)
        put32(static_cast<std::uint32_t>(layer.size()));
    for (const auto& layer : layers)
        out.insert(out.end(), layer.begin(), layer.end());
    return out;
}

} // namespace

LazLayout lazLayoutForFormat(int format, std::size_t extraBytes)
{
    LazLayout layout;
    layout.compressor = 3;
    layout.chunkSize = kChunkSize;
    layout.items.push_back({laz::kPoint14, 30, 3});
    if (format == 7)
        layout.items.push_back({laz::kRgb14, 6, 3});
    else if (format == 8)
        layout.items.push_back({laz::kRgbNir14, 8, 3});
    if (extraBytes > 0)
        layout.items.push_back({laz::kByte14, static_cast<std::uint16_t>(extraBytes), 3});
    return layout;
}

std::string lazRecordPayload(const LazLayout& layout)
{
    std::string s;
    put<std::uint16_t>(s, layout.compressor);
    put<std::uint16_t>(s, 0); // arithmetic coder
    // The LASzip version whose format this is (3.4 revision 3), and no options.
    s.push_back(3);
    s.push_back(4);
    put<std::uint16_t>(s, 3);
    put<std::uint32_t>(s, 0);
    put<std::uint32_t>(s, layout.chunkSize);
    put<std::int64_t>(s, -1); // no special EVLRs
    put<std::int64_t>(s, -1);
    put<std::uint16_t>(s, static_cast<std::uint16_t>(layout.items.size()));
    for (const LazItem& item : layout.items) {
        put<std::uint16_t>(s, item.type);
        put<std::uint16_t>(s, item.size);
        put<std::uint16_t>(s, item.version);
    }
    return s;
}

LazPointWriter::LazPointWriter(std::ostream& out, LazLayout layout, std::size_t recordLength)
    : out_(out), layout_(std::move(layout)), recordLength_(recordLength), tableOffsetAt_(out.tellp())
{
    const std::int64_t placeholder = -1;
    out_.write(reinterpret_cast<const char*>(&placeholder), sizeof placeholder);
}

void LazPointWriter::add(const char* records, std::size_t count)
{
    pending_.insert(pending_.end(), records, records + count * recordLength_);
    if (pending_.size() >= kChunksPerBatch * kChunkSize * recordLength_)
        flush(false);
}

void LazPointWriter::flush(bool all)
{
    const std::size_t points = pending_.size() / recordLength_;
    std::size_t chunks = points / kChunkSize;
    if (all && points % kChunkSize != 0)
        ++chunks;
    if (chunks == 0)
        return;
    std::vector<std::vector<unsigned char>> compressed(chunks);
    const auto* records = reinterpret_cast<const unsigned char*>(pending_.data());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, chunks, 1), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t c = r.begin(); c != r.end(); ++c) {
            const std::size_t first = c * kChunkSize;
            const std::size_t count = std::min<std::size_t>(kChunkSize, points - first);
            compressed[c] = compressChunk(layout_, records + first * recordLength_, count, recordLength_);
        }
    });
    std::size_t used = 0;
    for (std::size_t c = 0; c < chunks; ++c) {
        const std::size_t count = std::min<std::size_t>(kChunkSize, points - c * kChunkSize);
        out_.write(reinterpret_cast<const char*>(compressed[c].data()), static_cast<std::streamsize>(compressed[c].size()));
        chunkPoints_.push_back(static_cast<std::uint32_t>(count));
        chunkBytes_.push_back(static_cast<std::uint32_t>(compressed[c].size()));
        used += count;
    }
    pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(used * recordLength_));
}

void LazPointWriter::finish()
{
    flush(true);
    // The chunk table: version 0, the number of chunks, then each chunk's
    // byte count coded after the previous one's (32-bit integers, context 1;
    // point counts, context 0, only for variable chunks, which we do not write).
    const std::streamoff tableOffset = out_.tellp();
    std::string table;
    put<std::uint32_t>(table, 0);
    put<std::uint32_t>(table, static_cast<std::uint32_t>(chunkBytes_.size()));
    out_.write(table.data(), static_cast<std::streamsize>(table.size()));
    if (!chunkBytes_.empty()) {
        laz::ArithmeticEncoder encoder;
        laz::IntegerCoder sizes(32, 2);
        for (std::size_t i = 0; i < chunkBytes_.size(); ++i)
            sizes.compress(encoder, i ? static_cast<std::int32_t>(chunkBytes_[i - 1]) : 0, static_cast<std::int32_t>(chunkBytes_[i]), 1);
        const std::vector<unsigned char> bytes = encoder.done();
        out_.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    }
    const std::streamoff end = out_.tellp();
    const auto offset = static_cast<std::int64_t>(tableOffset);
    out_.seekp(tableOffsetAt_);
    out_.write(reinterpret_cast<const char*>(&offset), sizeof offset);
    out_.seekp(end);
}

} // namespace scandiff::io::detail
