// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The PLY reader's ASCII passes: the data section line by line, one record
//! per line, every token checked, with the line number in every message.

#include "ply/PlyLayout.h"

#include <scandiff/core/Progress.h>

#include "internal/TextUtil.h"

namespace scandiff::io::detail::ply {

//! Walks the data section line by line (one record per line, as every writer
//! does), skipping blank lines and keeping the line number for messages.
class AsciiLines
{
public:
    AsciiLines(const char* begin, const char* end, std::size_t firstLine)
        : ptr_(begin), end_(end), nextLineNumber_(firstLine)
    {
    }

    bool next(std::string_view& line)
    {
        while (ptr_ < end_) {
            const void* nl = std::memchr(ptr_, '\n', static_cast<std::size_t>(end_ - ptr_));
            const char* stop = nl ? static_cast<const char*>(nl) : end_;
            line = std::string_view(ptr_, static_cast<std::size_t>(stop - ptr_));
            ptr_ = nl ? stop + 1 : end_;
            lineNumber_ = nextLineNumber_++;
            for (char c : line)
                if (!isBlank(c))
                    return true;
        }
        return false;
    }
    std::size_t lineNumber() const { return lineNumber_; }
    //! The line the file ends on, for "the file ends at line N".
    std::size_t lastLine() const { return nextLineNumber_ - 1; }
    std::size_t remainingBytes() const { return static_cast<std::size_t>(end_ - ptr_); }

private:
    const char* ptr_;
    const char* end_;
    std::size_t nextLineNumber_;
    std::size_t lineNumber_ = 0;
};

class AsciiRecordReader
{
public:
    AsciiRecordReader(AsciiLines& lines, const PlyElement& e, const Context& ctx) : lines_(lines), e_(e), ctx_(ctx)
    {
        // A record holds at least one character and one separator or newline per
        // property: an upper bound on the records left, so that a corrupt count
        // cannot trigger a huge allocation.
        const std::size_t tokens = std::max<std::size_t>(e.properties.size(), 1);
        maxRecords_ = (lines.remainingBytes() + 1) / (2 * tokens);
    }

    //! Records that can be parsed before the data must run out (with a precise message).
    std::uint64_t capacity() const { return std::min<std::uint64_t>(e_.count, maxRecords_ + 1); }

    void beginRecord(std::uint64_t index)
    {
        index_ = index;
        if (!lines_.next(rest_))
            ctx_.fail("truncated: " + e_.name + " " + std::to_string(index + 1) + " of " + std::to_string(e_.count) +
                      " is missing (the file ends at line " + std::to_string(lines_.lastLine()) + ")");
    }
    std::string_view token(const PlyProperty& p)
    {
        std::string_view t;
        if (!nextToken(rest_, t))
            ctx_.failAtLine(lines_.lineNumber(), e_.name + " " + std::to_string(index_ + 1) + " has fewer values than the " +
                                                     std::to_string(e_.properties.size()) +
                                                     " properties of the header (no value for '" + p.name + "')");
        return t;
    }
    double number(const PlyProperty& p)
    {
        const std::string_view t = token(p);
        double v = 0.0;
        if (!parseDouble(t, v))
            ctx_.failAtLine(lines_.lineNumber(), quoted(t) + " is not a number (property '" + p.name + "' of " + e_.name +
                                                     " " + std::to_string(index_ + 1) + ")");
        return v;
    }
    std::int64_t integer(const PlyProperty& p)
    {
        const std::string_view t = token(p);
        std::int64_t v = 0;
        if (!parseInteger(t, v))
            ctx_.failAtLine(lines_.lineNumber(), quoted(t) + " is not an integer (property '" + p.name + "' of " +
                                                     e_.name + " " + std::to_string(index_ + 1) + ")");
        return v;
    }
    std::int64_t listCount(const PlyProperty& p)
    {
        const std::int64_t count = integer(p);
        if (count < 0)
            ctx_.failAtLine(lines_.lineNumber(), "negative length for list '" + p.name + "'");
        return count;
    }
    void endRecord()
    {
        std::string_view t;
        if (nextToken(rest_, t))
            ctx_.failAtLine(lines_.lineNumber(), e_.name + " " + std::to_string(index_ + 1) + " has more values than the " +
                                                     std::to_string(e_.properties.size()) + " properties of the header");
    }

private:
    AsciiLines& lines_;
    const PlyElement& e_;
    const Context& ctx_;
    std::string_view rest_;
    std::uint64_t index_ = 0;
    std::uint64_t maxRecords_ = 0;
};
//! Puts every vertex record's values into the sink (records from `reader`).
void readAsciiVertices(const PlyElement& e, const VertexLayout& layout, AsciiRecordReader& reader, const VertexSink& sink,
                       ProgressTicker& ticker);
//! Fan-triangulates every face record's vertex list (the list property `indexProperty`).
void readAsciiFaces(const PlyElement& e, std::size_t indexProperty, FaceBuilder& builder, AsciiLines& lines,
                    const Context& ctx, ProgressTicker& ticker);
//! Passes over an element's records, checking that the file holds them.
void skipAsciiElement(const PlyElement& e, AsciiLines& lines, const Context& ctx);

} // namespace scandiff::io::detail::ply
