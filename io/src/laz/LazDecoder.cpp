// SPDX-License-Identifier: GPL-3.0-or-later
//! LAZ decompression: the LASzip record, the chunk table and the chunks.
//! Each chunk starts with one uncompressed record and is decoded on its own,
//! so chunks are decoded in parallel. A pointwise chunk (LAS 1.0-1.3 records)
//! is one arithmetic stream after that record; a layered chunk (LAS 1.4) is
//! its point count, the byte count of every layer, then the layers. How LASzip
//! lays these out is described in its documentation and source
//! (github.com/LASzip/LASzip: laszip.hpp, lasreadpoint.cpp); this file follows
//! that description. The item coders are in laz/.

#include "laz/LazDecoder.h"
#include "laz/ArithmeticCoder.h"
#include "laz/Items.h"

#include <scandiff/core/Error.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <cstring>
#include <limits>
#include <memory>
#include <string>

namespace scandiff::io::detail {

namespace {

namespace fs = std::filesystem;
using laz::ArithmeticDecoder;
using laz::IntegerCoder;
using laz::load;

[[noreturn]] void invalid(const fs::path& path, const std::string& what)
{
    throw Error(ErrorCode::InvalidData, path.string() + ": " + what);
}

using Chunk = LazChunk;

//! Points between two checks of a stream for damage while decoding.
constexpr std::uint64_t kCheckEvery = 1024;
//! LASzip's coders spend at least a few thousandths of a bit on a point
//! (every adaptive model keeps a floor under each probability), so no chunk
//! holds more than about a thousand points per byte; ten thousand bounds what
//! a lying header or chunk table can make us allocate.
constexpr std::uint64_t kMaxPointsPerByte = 10000;

std::string chunkName(std::size_t index, const Chunk& chunk)
{
    return "LAZ chunk " + std::to_string(index) + " (from byte " + std::to_string(chunk.offset) + ")";
}

//! Decodes the records after the first of a pointwise chunk; returns the
//! bytes its stream used.
std::uint64_t decodePointwise(const fs::path& path, const LazLayout& layout, const unsigned char* first,
                              const unsigned char* end, const Chunk& chunk, std::size_t index, std::size_t recordLength,
                              char* out)
{
    std::vector<std::unique_ptr<laz::PointwiseItem>> items;
    std::vector<std::size_t> offsets;
    std::size_t at = 0;
    for (const LazItem& item : layout.items) {
        items.push_back(laz::makePointwiseItem(item.type, item.size, first + at));
        offsets.push_back(at);
        at += item.size;
    }
    ArithmeticDecoder decoder(first + recordLength, end);
    auto refuse = [&] {
        invalid(path, chunkName(index, chunk) + " is corrupt or truncated: its stream does not decode into " +
                          std::to_string(chunk.points) + " points");
    };
    for (std::uint64_t p = 1; p < chunk.points; ++p) {
        auto* record = reinterpret_cast<unsigned char*>(out + p * recordLength);
        for (std::size_t i = 0; i < items.size(); ++i)
            items[i]->decode(decoder, record + offsets[i]);
        // A damaged stream is given up soon, not after billions of points.
        if (p % kCheckEvery == 0 && decoder.corrupt())
            refuse();
    }
    // The encoder flushes exactly the bytes the decoder reads ahead: a whole
    // chunk is used up to its last byte, never beyond.
    if (decoder.corrupt())
        refuse();
    return static_cast<std::uint64_t>(decoder.position() - first);
}

//! What a worker decodes a chunk into, kept from one chunk to the next.
struct ChunkBuffers
{
    std::vector<char> records;
    //! The context the point14 item hands the other items, per point (layered chunks).
    std::vector<std::uint8_t> contexts;
};

//! Decodes the records after the first of a layered chunk into `out.records`;
//! returns the bytes the chunk holds (its count, layer sizes and layers).
std::uint64_t decodeLayered(const fs::path& path, const LazLayout& layout, const unsigned char* first,
                            const unsigned char* end, const Chunk& chunk, std::size_t index, std::size_t recordLength,
                            ChunkBuffers& buffers)
{
    char* out = buffers.records.data();
    std::vector<std::unique_ptr<laz::LayeredItem>> items;
    std::vector<std::size_t> offsets;
    std::size_t at = 0, layerCount = 0;
    for (const LazItem& item : layout.items) {
        items.push_back(laz::makeLayeredItem(item.type, item.size, first + at));
        offsets.push_back(at);
        at += item.size;
        layerCount += items.back()->layerCount();
    }
    const unsigned char* p = first + recordLength;
    auto remaining = [&] { return end > p ? static_cast<std::uint64_t>(end - p) : 0; };
    if (remaining() < 4 + 4 * layerCount)
        invalid(path, chunkName(index, chunk) + " is truncated before its layer sizes");
    const auto count = load<std::uint32_t>(p);
    if (count != chunk.points)
        invalid(path, chunkName(index, chunk) + " says it holds " + std::to_string(count) + " points, the chunk table " +
                          std::to_string(chunk.points));
    p += 4;
    std::vector<laz::Layer> layers(layerCount);
    for (laz::Layer& layer : layers) {
        layer.size = load<std::uint32_t>(p);
        p += 4;
    }
    for (laz::Layer& layer : layers) {
        if (layer.size > remaining())
            invalid(path, chunkName(index, chunk) + " is truncated: a layer of " + std::to_string(layer.size) +
                              " bytes runs past its end");
        layer.data = p;
        p += layer.size;
    }
    // The first layer, the returns and x, y, is never empty when there is a second point.
    if (chunk.points > 1 && layers.front().size == 0)
        invalid(path, chunkName(index, chunk) + " is corrupt: it has no x, y layer");
    std::uint32_t context = 0;
    std::size_t nextLayer = 0;
    for (auto& item : items) {
        item->start(layers.data() + nextLayer, context);
        nextLayer += item->layerCount();
    }
    auto corrupt = [&] { return std::any_of(items.begin(), items.end(), [](const auto& item) { return item->corrupt(); }); };
    auto refuse = [&] {
        invalid(path, chunkName(index, chunk) + " is corrupt: a layer does not decode into " + std::to_string(chunk.points) +
                          " points");
    };
    // One item at a time over the whole chunk: its layers are streams of
    // their own, so nothing ties an item's points to the other items' but
    // the context the point14 item hands them (laz/Items.h), kept here per
    // point. Decoding an item over all the points and then the next took
    // 0.92 of the time of decoding every item of a point before the next.
    // (The first point's entry is never read: the items start from `context`.)
    std::uint8_t* contexts = buffers.contexts.data();
    for (std::size_t i = 0; i < items.size(); ++i) {
        unsigned char* field = reinterpret_cast<unsigned char*>(out) + offsets[i];
        for (std::uint64_t q = 1; q < chunk.points; q += kCheckEvery) {
            const auto run = static_cast<std::size_t>(std::min<std::uint64_t>(kCheckEvery, chunk.points - q));
            items[i]->decodeRun(field + q * recordLength, recordLength, run, contexts + q);
            if (items[i]->corrupt())
                refuse();
        }
    }
    if (corrupt())
        refuse();
    // Each layer is a stream of its own, finished by its encoder: a damaged
    // one seldom ends on its last byte.
    if (!std::all_of(items.begin(), items.end(), [](const auto& item) { return item->endedExactly(); }))
        invalid(path, chunkName(index, chunk) + " is corrupt: a layer does not end where its size says");
    return static_cast<std::uint64_t>(p - first);
}

//! Decodes one chunk's records into `buffers.records` (sized for them);
//! returns the bytes it used.
std::uint64_t decodeChunk(const fs::path& path, const LazLayout& layout, const unsigned char* file, std::size_t fileSize,
                          const Chunk& chunk, std::size_t recordLength, std::size_t index, ChunkBuffers& buffers)
{
    char* out = buffers.records.data();
    if (chunk.points == 0)
        return 0;
    if (chunk.offset > fileSize || fileSize - chunk.offset < recordLength)
        invalid(path, chunkName(index, chunk) + " is too close to the end of the file (" + std::to_string(fileSize) +
                          " bytes) for its first record");
    // The first record of a chunk is stored as is; the coders start from it.
    const unsigned char* first = file + chunk.offset;
    std::memcpy(out, first, recordLength);
    const unsigned char* end = chunk.bytes ? first + chunk.bytes : file + fileSize;
    return layout.compressor == 3 ? decodeLayered(path, layout, first, end, chunk, index, recordLength, buffers)
                                  : decodePointwise(path, layout, first, end, chunk, index, recordLength, out);
}

//! The chunks of a chunked file, from its chunk table.
std::vector<Chunk> readChunkTable(const fs::path& path, const unsigned char* file, std::size_t size, std::uint64_t pointsStart,
                                  const LazLayout& layout, std::size_t recordLength, std::uint64_t count)
{
    if (pointsStart > size || size - pointsStart < 8)
        invalid(path, "LAZ point data (from byte " + std::to_string(pointsStart) + ") too short for the chunk table's offset");
    const std::uint64_t chunksStart = pointsStart + 8;
    auto tableOffset = load<std::int64_t>(file + pointsStart);
    if (tableOffset == -1 && size >= 8) // written to a stream: the offset is at the end of the file
        tableOffset = load<std::int64_t>(file + size - 8);
    if (tableOffset < 0 || static_cast<std::uint64_t>(tableOffset) < chunksStart ||
        static_cast<std::uint64_t>(tableOffset) > size || size - static_cast<std::uint64_t>(tableOffset) < 8)
        invalid(path, "the LAZ chunk table's offset (" + std::to_string(tableOffset) + ", at byte " +
                          std::to_string(pointsStart) + ") points outside the file (" + std::to_string(size) + " bytes)");
    const unsigned char* table = file + tableOffset;
    const auto version = load<std::uint32_t>(table);
    if (version != 0)
        invalid(path, "unknown LAZ chunk table version " + std::to_string(version) + " at byte " + std::to_string(tableOffset));
    const auto chunkCount = load<std::uint32_t>(table + 4);
    const std::uint64_t dataBytes = static_cast<std::uint64_t>(tableOffset) - chunksStart;
    // Every chunk holds at least its first record uncompressed.
    if (chunkCount > dataBytes / recordLength + (count == 0 ? 1 : 0))
        invalid(path, "the LAZ chunk table lists " + std::to_string(chunkCount) + " chunks, more than the " +
                          std::to_string(dataBytes) + " bytes of point data can hold");
    const bool variable = layout.chunkSize == UINT32_MAX;
    std::vector<Chunk> chunks(chunkCount);
    ArithmeticDecoder decoder(table + 8, file + size);
    IntegerCoder sizes(32, 2);
    for (std::size_t i = 0; i < chunkCount; ++i) {
        if (variable)
            chunks[i].points = static_cast<std::uint32_t>(sizes.decompress(decoder, i ? static_cast<std::int32_t>(chunks[i - 1].points) : 0, 0));
        chunks[i].bytes = static_cast<std::uint32_t>(sizes.decompress(decoder, i ? static_cast<std::int32_t>(chunks[i - 1].bytes) : 0, 1));
    }
    if (decoder.bytesPastEnd() > 0)
        invalid(path, "the LAZ chunk table at byte " + std::to_string(tableOffset) + " is truncated");
    std::uint64_t offset = chunksStart, point = 0;
    for (std::size_t i = 0; i < chunkCount; ++i) {
        Chunk& c = chunks[i];
        c.offset = offset;
        c.firstPoint = point;
        if (!variable)
            c.points = std::min<std::uint64_t>(layout.chunkSize, count - std::min(count, point));
        if (c.bytes > static_cast<std::uint64_t>(tableOffset) - offset)
            invalid(path, "LAZ chunk " + std::to_string(i) + " (" + std::to_string(c.bytes) + " bytes from byte " +
                              std::to_string(offset) + ") runs past the chunk table at byte " + std::to_string(tableOffset));
        // A chunk holds at least its first record (and, layered, its point count).
        const std::uint64_t minimum = recordLength + (layout.compressor == 3 ? 4 : 0);
        if (c.points > 0 && (c.bytes < minimum || c.points / kMaxPointsPerByte > c.bytes))
            invalid(path, "LAZ chunk " + std::to_string(i) + " cannot hold " + std::to_string(c.points) + " points in " +
                              std::to_string(c.bytes) + " bytes");
        offset += c.bytes;
        point += c.points;
    }
    if (point != count)
        invalid(path, "the LAZ chunk table accounts for " + std::to_string(point) + " points, the header says " +
                          std::to_string(count));
    return chunks;
}

} // namespace

LazLayout parseLazLayout(const fs::path& path, const char* payload, std::size_t length, std::size_t recordLength)
{
    constexpr std::size_t kFixedPart = 34, kItemSize = 6;
    if (length < kFixedPart)
        invalid(path, "the LASzip record is " + std::to_string(length) + " bytes, shorter than its fixed " +
                          std::to_string(kFixedPart));
    LazLayout layout;
    layout.compressor = load<std::uint16_t>(payload);
    const auto coder = load<std::uint16_t>(payload + 2);
    layout.chunkSize = load<std::uint32_t>(payload + 12);
    const auto itemCount = load<std::uint16_t>(payload + 32);
    if (kFixedPart + kItemSize * itemCount > length)
        invalid(path, "the LASzip record lists " + std::to_string(itemCount) + " items, more than its " +
                          std::to_string(length) + " bytes hold");
    if (coder != 0)
        throw Error(ErrorCode::Unsupported, path.string() + ": LAZ entropy coder " + std::to_string(coder) +
                                                " is not known (0, arithmetic, is the only one LASzip defines)");
    std::size_t total = 0;
    for (std::size_t i = 0; i < itemCount; ++i) {
        const char* p = payload + kFixedPart + kItemSize * i;
        LazItem item{load<std::uint16_t>(p), load<std::uint16_t>(p + 2), load<std::uint16_t>(p + 4)};
        total += item.size;
        layout.items.push_back(item);
    }
    if (total != recordLength)
        invalid(path, "the LASzip items add up to " + std::to_string(total) + " bytes per point, the header's record length is " +
                          std::to_string(recordLength));
    if (layout.compressor < 1 || layout.compressor > 3)
        invalid(path, "unknown LAZ compressor " + std::to_string(layout.compressor) + " in the LASzip record");
    if (layout.compressor >= 2 && layout.chunkSize == 0)
        layout.chunkSize = UINT32_MAX; // LASzip reads a chunk size of 0 as "given per chunk"
    const bool layered = layout.compressor == 3;
    for (const LazItem& item : layout.items) {
        using namespace laz;
        const bool known = layered ? (item.type == kPoint14 && item.size == 30) || (item.type == kRgb14 && item.size == 6) ||
                                         (item.type == kRgbNir14 && item.size == 8) || (item.type == kByte14 && item.size > 0)
                                   : (item.type == kPoint10 && item.size == 20) || (item.type == kGpsTime11 && item.size == 8) ||
                                         (item.type == kRgb12 && item.size == 6) || (item.type == kByte && item.size > 0);
        if (!known)
            throw Error(ErrorCode::Unsupported, path.string() + ": LAZ item " + itemName(item.type) + " of " +
                                                    std::to_string(item.size) + " bytes cannot be read" +
                                                    (layered ? " from layered chunks" : ""));
        const std::uint16_t version = layered ? 3 : 2;
        if (item.version != version)
            throw Error(ErrorCode::Unsupported,
                        path.string() + ": LAZ item " + itemName(item.type) + " version " + std::to_string(item.version) +
                            " cannot be read (version " + std::to_string(version) + ", what LASzip writes" +
                            (layered ? " for LAS 1.4 points, can)" : " since 2011, can)"));
    }
    // The layered coders begin with the point14 item: it sets the context the
    // others follow. It comes once: a second one would find its x, y layer
    // unchecked (the chunk's first layer is the only one that must not be empty).
    if (layered && (layout.items.empty() || layout.items.front().type != laz::kPoint14))
        invalid(path, "the LASzip record's layered items do not start with point14");
    if (layered && std::count_if(layout.items.begin(), layout.items.end(),
                                 [](const LazItem& item) { return item.type == laz::kPoint14; }) > 1)
        invalid(path, "the LASzip record has more than one point14 item");
    return layout;
}

std::uint64_t lazFirstRecordOffset(const LazLayout& layout, std::uint64_t pointsStart, std::size_t recordLength,
                                   std::size_t fileSize)
{
    // Chunked files put the chunk table's offset (8 bytes) before the first chunk.
    const std::uint64_t at = pointsStart + (layout.compressor == 1 ? 0 : 8);
    return at <= fileSize && fileSize - at >= recordLength ? at : 0;
}

std::vector<LazChunk> readLazChunks(const fs::path& path, const char* data, std::size_t size, std::uint64_t pointsStart,
                                    const LazLayout& layout, std::size_t recordLength, std::uint64_t count)
{
    const auto* file = reinterpret_cast<const unsigned char*>(data);
    if (count == 0)
        return {};
    if (layout.compressor == 1) {
        if (pointsStart > size || count / kMaxPointsPerByte > size - pointsStart)
            invalid(path, "the header claims " + std::to_string(count) + " points, more than the " +
                              std::to_string(pointsStart > size ? 0 : size - pointsStart) + " bytes of compressed points can hold");
        return {Chunk{pointsStart, 0, 0, count}};
    }
    return readChunkTable(path, file, size, pointsStart, layout, recordLength, count);
}

void decompressLazRecords(const fs::path& path, const char* data, std::size_t size, const std::vector<LazChunk>& chunks,
                          const LazLayout& layout, std::size_t recordLength, std::uint64_t first, std::uint64_t wanted,
                          const LazRecordsConsumer& consume, const std::function<void(std::size_t)>& progress)
{
    const auto* file = reinterpret_cast<const unsigned char*>(data);
    const std::uint64_t count = chunks.empty() ? 0 : chunks.back().firstPoint + chunks.back().points;
    first = std::min(first, count);
    const std::uint64_t last = first + std::min(wanted, count - first);
    // Only the chunks that hold records of the range.
    const auto from = std::partition_point(chunks.begin(), chunks.end(),
                                           [&](const Chunk& c) { return c.firstPoint + c.points <= first; });
    const auto to = std::partition_point(from, chunks.end(), [&](const Chunk& c) { return c.firstPoint < last; });
    const std::size_t begin = static_cast<std::size_t>(from - chunks.begin());
    const std::size_t end = static_cast<std::size_t>(to - chunks.begin());
    // Each worker decodes into its own buffer of a chunk's records (about 2 MB
    // for LASzip's 50,000 points), which stays in its cache while the
    // consumer takes the records from it: no buffer of the whole file.
    tbb::enumerable_thread_specific<ChunkBuffers> workerBuffers;
    // A few chunks per worker between two calls of `progress`: Cancel is heard
    // within a few chunks' time (about 10 ms each for 50,000 points).
    const std::size_t batch = 8;
    for (std::size_t b = begin; b < end; b += batch) {
        const std::size_t e = std::min(end, b + batch);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(b, e, 1), [&](const tbb::blocked_range<std::size_t>& r) {
            ChunkBuffers& buffers = workerBuffers.local();
            for (std::size_t i = r.begin(); i != r.end(); ++i) {
                const Chunk& chunk = chunks[i];
                if (chunk.points == 0)
                    continue;
                if (chunk.points > std::numeric_limits<std::size_t>::max() / recordLength)
                    invalid(path, chunkName(i, chunk) + " holds more points than memory can");
                try {
                    buffers.records.resize(static_cast<std::size_t>(chunk.points) * recordLength);
                    if (layout.compressor == 3)
                        buffers.contexts.resize(static_cast<std::size_t>(chunk.points));
                } catch (const std::bad_alloc&) {
                    throw Error(ErrorCode::Io, path.string() + ": not enough memory to decompress " + chunkName(i, chunk));
                }
                const std::uint64_t used = decodeChunk(path, layout, file, size, chunk, recordLength, i, buffers);
                if (chunk.bytes != 0 && chunk.points > 1 && used != chunk.bytes)
                    invalid(path, chunkName(i, chunk) + " is corrupt: its " + std::to_string(chunk.points) + " points use " +
                                      std::to_string(used) + " of its " + std::to_string(chunk.bytes) + " bytes");
                const std::uint64_t lo = std::max(first, chunk.firstPoint);
                const std::uint64_t hi = std::min(last, chunk.firstPoint + chunk.points);
                consume(lo, buffers.records.data() + (lo - chunk.firstPoint) * recordLength, static_cast<std::size_t>(hi - lo));
            }
        });
        std::uint64_t points = 0;
        for (std::size_t i = b; i < e; ++i)
            points += std::min(last, chunks[i].firstPoint + chunks[i].points) - std::max(first, chunks[i].firstPoint);
        progress(static_cast<std::size_t>(points));
    }
}

std::vector<std::uint8_t> lazBitsZeroInEveryRecord(const char* data, std::size_t size, const std::vector<LazChunk>& chunks,
                                                   const LazLayout& layout, std::size_t recordLength)
{
    std::vector<std::uint8_t> zero(recordLength, 0);
    if (layout.compressor != 3 || chunks.empty())
        return zero;
    // Each layer's bits at their place in the record.
    std::vector<std::vector<std::uint8_t>> layers;
    std::size_t at = 0;
    for (const LazItem& item : layout.items) {
        for (const std::vector<std::uint8_t>& bits : laz::layerBits(item.type, item.size)) {
            layers.emplace_back(recordLength, 0);
            std::copy(bits.begin(), bits.end(), layers.back().begin() + static_cast<std::ptrdiff_t>(at));
        }
        at += item.size;
    }
    for (const std::vector<std::uint8_t>& bits : layers)
        for (std::size_t b = 0; b < recordLength; ++b)
            zero[b] |= bits[b];
    const auto* file = reinterpret_cast<const unsigned char*>(data);
    for (const LazChunk& chunk : chunks) {
        if (chunk.points == 0)
            continue;
        const std::uint64_t head = recordLength + 4 + 4 * layers.size();
        if (chunk.offset > size || size - chunk.offset < head)
            return std::vector<std::uint8_t>(recordLength, 0);
        const unsigned char* first = file + chunk.offset;
        const unsigned char* sizes = first + recordLength + 4;
        for (std::size_t l = 0; l < layers.size(); ++l) {
            // An empty layer: its bits as in the first record; else anything.
            const bool empty = chunk.points == 1 || load<std::uint32_t>(sizes + 4 * l) == 0;
            for (std::size_t b = 0; b < recordLength; ++b)
                zero[b] &= static_cast<std::uint8_t>(~(layers[l][b] & (empty ? first[b] : 0xFF)));
        }
    }
    return zero;
}

std::unique_ptr<char[]> decompressLaz(const fs::path& path, const char* data, std::size_t size, std::uint64_t pointsStart,
                                      const LazLayout& layout, std::size_t recordLength, std::uint64_t count,
                                      const std::function<void(std::size_t)>& progress)
{
    if (count > std::numeric_limits<std::size_t>::max() / recordLength)
        invalid(path, std::to_string(count) + " points of " + std::to_string(recordLength) + " bytes do not fit in memory");
    // The chunk table vouches for the count before anything is allocated for it.
    const std::vector<LazChunk> chunks = readLazChunks(path, data, size, pointsStart, layout, recordLength, count);
    // Not zeroed: every byte is written (zeroing costs a quarter of the decoding time).
    std::unique_ptr<char[]> out;
    try {
        out.reset(new char[std::max<std::size_t>(1, static_cast<std::size_t>(count) * recordLength)]);
    } catch (const std::bad_alloc&) {
        throw Error(ErrorCode::Io, path.string() + ": not enough memory to decompress " + std::to_string(count) + " points");
    }
    decompressLazRecords(
        path, data, size, chunks, layout, recordLength, 0, count,
        [&](std::uint64_t firstPoint, const char* records, std::size_t n) {
            std::memcpy(out.get() + firstPoint * recordLength, records, n * recordLength);
        },
        progress);
    return out;
}

} // namespace scandiff::io::detail
