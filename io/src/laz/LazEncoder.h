// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! LAZ writing (internal to io/): LAS 1.4 point records (formats 6-8 and
//! extra bytes) compressed as LASzip's layered chunks, which any LAZ 1.4
//! reader decodes.

#include "laz/LazDecoder.h"

#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

namespace scandiff::io::detail {

//! The layout of records of point format 6, 7 or 8 followed by `extraBytes`
//! bytes: items point14, rgb14 or rgbnir14, byte14; chunks of 50,000 points.
LazLayout lazLayoutForFormat(int format, std::size_t extraBytes);

//! The payload of the LASzip record ("laszip encoded", 22204) for `layout`.
std::string lazRecordPayload(const LazLayout& layout);

//! Writes the compressed point data of a LAZ file to `out`, from where the
//! points start: the chunk table's offset, the chunks, the chunk table.
//! Records come in any number at a time; full chunks are compressed in
//! parallel in batches.
class LazPointWriter
{
public:
    LazPointWriter(std::ostream& out, LazLayout layout, std::size_t recordLength);
    void add(const char* records, std::size_t count);
    //! Compresses what is left and writes the chunk table.
    void finish();

private:
    void flush(bool all);

    std::ostream& out_;
    LazLayout layout_;
    std::size_t recordLength_;
    std::streamoff tableOffsetAt_;
    std::vector<char> pending_; //!< records not compressed yet
    std::vector<std::uint32_t> chunkPoints_, chunkBytes_;
};

} // namespace scandiff::io::detail
