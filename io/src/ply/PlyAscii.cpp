// SPDX-License-Identifier: GPL-3.0-or-later
//! The PLY reader's ASCII passes (ply/PlyAscii.h).

#include "ply/PlyAscii.h"

namespace scandiff::io::detail::ply {

void readAsciiVertices(const PlyElement& e, const VertexLayout& layout, AsciiRecordReader& reader, const VertexSink& sink,
                       ProgressTicker& ticker)
{
    const std::uint64_t capacity = reader.capacity();
    for (std::uint64_t i = 0; i < e.count; ++i) {
        if (i == capacity) // cannot happen (see capacity()), but the arrays end here
            throw Error(ErrorCode::Internal, "PLY reader: ASCII record bound exceeded");
        reader.beginRecord(i);
        for (std::size_t j = 0; j < e.properties.size(); ++j) {
            const PlyProperty& p = e.properties[j];
            if (p.isList) {
                for (std::int64_t k = reader.listCount(p); k > 0; --k)
                    reader.token(p);
            } else if (const int slot = layout.slotOfProperty[j]; slot >= 0) {
                sink.put(i, layout.slots[static_cast<std::size_t>(slot)], reader.number(p));
            } else {
                reader.token(p);
            }
        }
        reader.endRecord();
        if ((i + 1) % kChunk == 0)
            ticker.step(kChunk);
    }
    ticker.step(e.count % kChunk);
}

void readAsciiFaces(const PlyElement& e, std::size_t indexProperty, FaceBuilder& builder, AsciiLines& lines,
                    const Context& ctx, ProgressTicker& ticker)
{
    AsciiRecordReader reader(lines, e, ctx);
    for (std::uint64_t i = 0; i < e.count; ++i) {
        reader.beginRecord(i);
        for (std::size_t j = 0; j < e.properties.size(); ++j) {
            const PlyProperty& p = e.properties[j];
            if (!p.isList) {
                reader.token(p);
                continue;
            }
            const std::int64_t count = reader.listCount(p);
            if (j == indexProperty)
                builder.begin(i);
            for (std::int64_t k = 0; k < count; ++k) {
                if (j == indexProperty)
                    builder.add(reader.integer(p));
                else
                    reader.token(p);
            }
        }
        reader.endRecord();
        if ((i + 1) % kChunk == 0)
            ticker.step(kChunk);
    }
    ticker.step(e.count % kChunk);
}

void skipAsciiElement(const PlyElement& e, AsciiLines& lines, const Context& ctx)
{
    AsciiRecordReader reader(lines, e, ctx);
    for (std::uint64_t i = 0; i < e.count; ++i)
        reader.beginRecord(i);
}
} // namespace scandiff::io::detail::ply
