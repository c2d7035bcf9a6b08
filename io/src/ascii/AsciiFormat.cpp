// SPDX-License-Identifier: GPL-3.0-or-later
//! ASCII point files: .xyz .txt .csv .pts .asc .neu, one point per line.
//!
//! How a file is understood (these rules are user documentation, keep the README in step):
//!
//! - Separator: ReadOptions::asciiSeparator if given, else taken from the first
//!   data row: ',' if it holds one, else ';', else runs of spaces and tabs.
//!   Around ',' and ';' spaces are ignored, and one trailing separator is allowed.
//! - Header: the leading lines that are not made of numbers only are header
//!   lines (ReadOptions::asciiSkipLines sets how many lines to skip instead).
//!   The last header line whose tokens are as many as the data columns and name
//!   x, y and z gives the column names; a leading "//" or "#" is removed and
//!   names are case-insensitive: x y z; r g b or red green blue (0-255);
//!   rf gf bf (0-1); nx ny nz; intensity; skip (column ignored); any other name
//!   becomes a scalar field of that name.
//! - Leica PTS: a data line holding a single integer (the point count) before
//!   the points is skipped, as are the counts of the following scans when several
//!   are concatenated. Such a file, or a .pts file, with 4 columns is
//!   x y z intensity, with 7 columns x y z intensity r g b.
//! - Without names, the number of columns decides (the first 256 rows are looked at):
//!     3: x y z
//!     6: x y z r g b if columns 4-6 are integers within 0-255 (one above 1),
//!        else x y z nx ny nz if they are within -1..1, else fields
//!     7: x y z intensity r g b if columns 5-7 are integers within 0-255, else fields
//!     9: x y z r g b nx ny nz if the values fit, else fields
//!     other counts: x y z then scalar fields "field_4", "field_5"... named after
//!     their column number.
//! - ReadOptions::asciiColumns replaces the mapping, one name per column.
//! - After the header, blank lines and lines starting with '#' or '//' are
//!   skipped. Every other line must have as many values as the first data row
//!   and hold numbers only ("nan" is a missing scalar value).
//! - Coordinates are read as double; the origin is ReadOptions::origin or
//!   suggestOrigin() of their bounding box. A field whose values are large
//!   (GPS time) is stored relative to its first value rounded down.
//!
//! Writing: a "//X Y Z R G B Nx Ny Nz <fields>" header line (only the attributes
//! present), then one line per point with global coordinates at
//! WriteOptions::asciiPrecision decimals. The separator is ',' for .csv and a
//! space otherwise; missing scalar values are written "nan".

#include "internal/Formats.h"
#include "internal/MappedFile.h"
#include "internal/TextUtil.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/Log.h>
#include <scandiff/io/AtomicFile.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>
#include <unordered_set>
#include <vector>

namespace scandiff::io::detail {

namespace {

namespace fs = std::filesystem;

//! Rows per progress step and per cancellation check.
constexpr std::size_t kRowsPerStep = 1u << 16;
//! Rows looked at to guess what unnamed columns hold.
constexpr std::size_t kSampleRows = 256;

std::string lower(std::string_view s)
{
    std::string out(s);
    for (char& c : out)
        if (c >= 'A' && c <= 'Z')
            c = static_cast<char>(c - 'A' + 'a');
    return out;
}

bool isBlank(char c)
{
    return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v';
}

std::string_view trim(std::string_view s)
{
    while (!s.empty() && isBlank(s.front()))
        s.remove_prefix(1);
    while (!s.empty() && isBlank(s.back()))
        s.remove_suffix(1);
    return s;
}

bool isCommentLine(std::string_view trimmed)
{
    return (!trimmed.empty() && trimmed[0] == '#') || trimmed.substr(0, 2) == "//";
}

bool isInteger(std::string_view token)
{
    std::int64_t value = 0;
    const auto [ptr, ec] = std::from_chars(token.data(), token.data() + token.size(), value);
    return ec == std::errc() && ptr == token.data() + token.size() && !token.empty();
}

//! Lines of the mapped file with their 1-based numbers; copyable to look ahead.
class LineCursor
{
public:
    LineCursor(const char* begin, const char* end) : ptr_(begin), begin_(begin), end_(end) {}

    bool next(std::string_view& line)
    {
        if (ptr_ >= end_)
            return false;
        const void* nl = std::memchr(ptr_, '\n', static_cast<std::size_t>(end_ - ptr_));
        const char* stop = nl ? static_cast<const char*>(nl) : end_;
        line = std::string_view(ptr_, static_cast<std::size_t>(stop - ptr_));
        if (!line.empty() && line.back() == '\r')
            line.remove_suffix(1);
        ptr_ = nl ? stop + 1 : end_;
        ++lineNumber_;
        return true;
    }
    //! Number of the line last returned by next().
    std::size_t lineNumber() const { return lineNumber_; }
    std::size_t offset() const { return static_cast<std::size_t>(ptr_ - begin_); }

private:
    const char* ptr_;
    const char* begin_;
    const char* end_;
    std::size_t lineNumber_ = 0;
};

//! More values than this in a row is not a table of points (the widest real
//! exports hold a few dozen attributes). Splitting stops one value past it, so
//! a hostile single line of a gigabyte costs no more than a normal row.
constexpr std::size_t kMaxColumns = 1024;

//! Splits a line into values (at most kMaxColumns + 1). Whitespace mode takes
//! runs of spaces and tabs as one separator; character mode splits on one
//! character and trims the values.
class Splitter
{
public:
    explicit Splitter(char separator) : separator_(separator), whitespace_(separator == ' ' || separator == '\t') {}
    char separator() const { return separator_; }

    void split(std::string_view line, std::vector<std::string_view>& tokens) const
    {
        tokens.clear();
        if (whitespace_) {
            std::size_t i = 0;
            while (i < line.size()) {
                while (i < line.size() && isBlank(line[i]))
                    ++i;
                const std::size_t start = i;
                while (i < line.size() && !isBlank(line[i]))
                    ++i;
                if (i > start)
                    tokens.push_back(line.substr(start, i - start));
                if (tokens.size() > kMaxColumns)
                    return;
            }
            return;
        }
        line = trim(line);
        if (line.empty())
            return;
        // "1,2,3," is common in spreadsheet exports.
        if (line.back() == separator_)
            line.remove_suffix(1);
        std::size_t start = 0;
        while (true) {
            const std::size_t pos = line.find(separator_, start);
            tokens.push_back(trim(line.substr(start, pos == std::string_view::npos ? std::string_view::npos : pos - start)));
            if (pos == std::string_view::npos || tokens.size() > kMaxColumns)
                break;
            start = pos + 1;
        }
    }

private:
    char separator_;
    bool whitespace_;
};

//! Splits on any usual separator (at most kMaxColumns + 1 values): for deciding
//! whether a line is data or header before the separator is known.
void splitAny(std::string_view line, std::vector<std::string_view>& tokens)
{
    tokens.clear();
    auto isSeparator = [](char c) { return isBlank(c) || c == ',' || c == ';'; };
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && isSeparator(line[i]))
            ++i;
        const std::size_t start = i;
        while (i < line.size() && !isSeparator(line[i]))
            ++i;
        if (i > start)
            tokens.push_back(line.substr(start, i - start));
        if (tokens.size() > kMaxColumns)
            return;
    }
}

// ---------------------------------------------------------------- column mapping

enum class Role : std::uint8_t { Skip, X, Y, Z, Red, Green, Blue, Nx, Ny, Nz, Field };

struct Column
{
    Role role = Role::Skip;
    double colorScale = 1.0; //!< 255 for 0-1 colours
    std::size_t field = 0;   //!< index in Mapping::fieldNames for Role::Field
};

struct Mapping
{
    std::vector<Column> columns;
    std::vector<std::string> fieldNames;
    std::unordered_set<std::string> usedNames; // fieldNames as a set: a new name is checked in constant time

    bool has(Role role) const
    {
        return std::any_of(columns.begin(), columns.end(), [role](const Column& c) { return c.role == role; });
    }
    bool hasXyz() const { return has(Role::X) && has(Role::Y) && has(Role::Z); }
    bool hasColors() const { return has(Role::Red) || has(Role::Green) || has(Role::Blue); }
    bool hasNormals() const { return has(Role::Nx) || has(Role::Ny) || has(Role::Nz); }

    void addField(std::string name)
    {
        const std::string base = name;
        for (int k = 2; usedNames.count(name) != 0; ++k)
            name = base + "_" + std::to_string(k);
        usedNames.insert(name);
        Column c;
        c.role = Role::Field;
        c.field = fieldNames.size();
        fieldNames.push_back(std::move(name));
        columns.push_back(c);
    }
    void add(Role role, double colorScale = 1.0)
    {
        Column c;
        c.role = role;
        c.colorScale = colorScale;
        columns.push_back(c);
    }
    //! Maps a column name of a header or of ReadOptions::asciiColumns.
    void addNamed(std::string_view name)
    {
        const std::string key = lower(name);
        struct Known
        {
            const char* name;
            Role role;
            double colorScale;
        };
        static const Known known[] = {
            {"x", Role::X, 1},       {"y", Role::Y, 1},         {"z", Role::Z, 1},          {"r", Role::Red, 1},
            {"g", Role::Green, 1},   {"b", Role::Blue, 1},      {"red", Role::Red, 1},      {"green", Role::Green, 1},
            {"blue", Role::Blue, 1}, {"rf", Role::Red, 255},    {"gf", Role::Green, 255},   {"bf", Role::Blue, 255},
            {"nx", Role::Nx, 1},     {"ny", Role::Ny, 1},       {"nz", Role::Nz, 1},        {"skip", Role::Skip, 1},
        };
        for (const Known& k : known)
            if (key == k.name) {
                add(k.role, k.colorScale);
                return;
            }
        addField(key == "intensity" ? key : std::string(name));
    }
};

//! What the first rows show about each column, to guess unnamed columns.
struct ColumnStats
{
    bool colorIntegers = true; //!< every value an integer within 0-255
    bool aboveOne = false;     //!< some value above 1 (colours rather than normals)
    bool unit = true;          //!< every value within -1..1
};

Mapping mappingByCount(std::size_t count, const std::vector<ColumnStats>& stats, bool pts)
{
    auto colorLike = [&](std::size_t first, bool needAboveOne) {
        bool above = false;
        for (std::size_t c = first; c < first + 3; ++c) {
            if (!stats[c].colorIntegers)
                return false;
            above = above || stats[c].aboveOne;
        }
        return above || !needAboveOne;
    };
    auto unitLike = [&](std::size_t first) {
        return stats[first].unit && stats[first + 1].unit && stats[first + 2].unit;
    };
    Mapping m;
    m.add(Role::X);
    m.add(Role::Y);
    m.add(Role::Z);
    auto rgb = [&] {
        m.add(Role::Red);
        m.add(Role::Green);
        m.add(Role::Blue);
    };
    auto normals = [&] {
        m.add(Role::Nx);
        m.add(Role::Ny);
        m.add(Role::Nz);
    };
    if (count == 4 && pts) {
        m.addField("intensity");
    } else if (count == 6 && colorLike(3, true)) {
        rgb();
    } else if (count == 6 && unitLike(3)) {
        normals();
    } else if (count == 7 && (pts || colorLike(4, false))) {
        m.addField("intensity");
        rgb();
    } else if (count == 9 && colorLike(3, false) && unitLike(6)) {
        rgb();
        normals();
    } else {
        for (std::size_t c = 3; c < count; ++c)
            m.addField("field_" + std::to_string(c + 1));
    }
    return m;
}

//! Keeps float precision for large values (GPS time ~1e9 s): values are stored
//! relative to the first one rounded down.
double chooseFieldOffset(double firstValue)
{
    if (!std::isfinite(firstValue) || std::abs(firstValue) < 1e5)
        return 0.0;
    return std::floor(firstValue);
}

//! Whether a field stored as a float around `offset` writes `text` back with
//! the same value. Without an offset the writer prints the float's shortest
//! form, which gives back any number of at most 6 significant digits (FLT_DIG);
//! longer ones are checked by printing. With an offset the value is printed as
//! a double, so the float must hold it exactly.
bool floatKeeps(std::string_view text, double v, double offset)
{
    if (offset != 0.0)
        return offset + static_cast<double>(static_cast<float>(v - offset)) == v;
    int digits = 0;
    bool leading = true;
    for (char ch : text) {
        if (ch == 'e' || ch == 'E')
            break;
        if (ch < '0' || ch > '9')
            continue;
        if (leading && ch == '0')
            continue;
        leading = false;
        ++digits;
    }
    if (digits <= 6)
        return true;
    char buffer[32];
    const auto printed = std::to_chars(buffer, buffer + sizeof buffer, static_cast<float>(v));
    double back = 0.0;
    std::from_chars(buffer, printed.ptr, back);
    return back == v;
}

// ---------------------------------------------------------------- reading

class AsciiReader
{
public:
    AsciiReader(const fs::path& path, const ReadOptions& options)
        : path_(path), fileName_(path.string()), options_(options), file_(path),
          cursor_(file_.data(), file_.data() + file_.size())
    {
    }

    PointCloud read()
    {
        if (file_.size() == 0)
            fail("empty file");
        ProgressTicker ticker(options_.progress, "Reading " + path_.filename().string(), file_.size());
        const std::vector<std::string_view> headerLines = skipHeader();
        findFirstDataRow();
        const Splitter splitter(options_.asciiSeparator ? *options_.asciiSeparator : detectSeparator(firstRow_));
        std::vector<std::string_view> tokens;
        splitter.split(firstRow_, tokens);
        columnCount_ = tokens.size();
        if (columnCount_ > kMaxColumns)
            failAtLine(firstRowLine_, "more than " + std::to_string(kMaxColumns) + " values in a row: not a table of points");
        if (columnCount_ < 3)
            failAtLine(firstRowLine_, "a point needs at least 3 values (x y z), found " + std::to_string(columnCount_));
        mapping_ = chooseMapping(headerLines, splitter);
        parseRows(splitter, ticker);
        return buildCloud();
    }

private:
    [[noreturn]] void fail(const std::string& message) const
    {
        throw Error(ErrorCode::InvalidData, fileName_ + ": " + message);
    }
    [[noreturn]] void failAtLine(std::size_t line, const std::string& message) const
    {
        throw Error(ErrorCode::InvalidData, fileName_ + ":" + std::to_string(line) + ": " + message);
    }

    //! True for a line of numbers only (with asciiColumns, "skip" columns may hold text).
    bool isDataRow(std::string_view line)
    {
        splitAny(line, scratch_);
        if (scratch_.empty())
            return false;
        const auto* names = options_.asciiColumns ? &options_.asciiColumns->names : nullptr;
        if (names && names->size() != scratch_.size())
            names = nullptr;
        for (std::size_t i = 0; i < scratch_.size(); ++i) {
            if (names && lower((*names)[i]) == "skip")
                continue;
            double v;
            if (!parseDouble(scratch_[i], v))
                return false;
        }
        return true;
    }

    //! Consumes the header lines and returns them; the cursor then stands before the data.
    std::vector<std::string_view> skipHeader()
    {
        std::vector<std::string_view> header;
        std::string_view line;
        if (options_.asciiSkipLines) {
            for (std::size_t i = 0; i < *options_.asciiSkipLines; ++i) {
                if (!cursor_.next(line))
                    fail("no data row: the file has fewer than " + std::to_string(*options_.asciiSkipLines) +
                         " lines to skip");
                if (!trim(line).empty())
                    header.push_back(line);
            }
            return header;
        }
        while (true) {
            LineCursor before = cursor_;
            if (!cursor_.next(line))
                fail("no data row: no line holds numbers only");
            if (trim(line).empty())
                continue;
            if (isDataRow(line)) {
                cursor_ = before;
                return header;
            }
            header.push_back(line);
        }
    }

    //! Reads the first data row, skipping a PTS point count before it.
    void findFirstDataRow()
    {
        if (!nextDataLine(firstRow_))
            fail("no data row after the header");
        firstRowLine_ = cursor_.lineNumber();
        pts_ = lowerExtension(path_) == "pts";
        splitAny(firstRow_, scratch_);
        if (scratch_.size() == 1 && isInteger(scratch_[0])) {
            const LineCursor afterCount = cursor_;
            std::string_view next;
            bool isCount = false;
            if (nextDataLine(next)) {
                splitAny(next, scratch_);
                isCount = scratch_.size() > 1;
            }
            if (isCount) {
                pts_ = true;
                firstRow_ = next;
                firstRowLine_ = cursor_.lineNumber();
            } else {
                cursor_ = afterCount;
            }
        }
        dataStart_ = cursor_;
    }

    //! Next line that is neither blank nor a comment.
    bool nextDataLine(std::string_view& line)
    {
        while (cursor_.next(line)) {
            const std::string_view t = trim(line);
            if (!t.empty() && !isCommentLine(t))
                return true;
        }
        return false;
    }

    static char detectSeparator(std::string_view row)
    {
        if (row.find(',') != std::string_view::npos)
            return ',';
        if (row.find(';') != std::string_view::npos)
            return ';';
        return ' ';
    }

    Mapping chooseMapping(const std::vector<std::string_view>& headerLines, const Splitter& splitter)
    {
        if (options_.asciiColumns) {
            const auto& names = options_.asciiColumns->names;
            if (names.size() != columnCount_)
                throw Error(ErrorCode::InvalidArgument, fileName_ + ":" + std::to_string(firstRowLine_) +
                                                            ": the column mapping names " + std::to_string(names.size()) +
                                                            " columns but the data has " + std::to_string(columnCount_));
            Mapping m;
            for (const auto& name : names)
                m.addNamed(name);
            if (!m.hasXyz())
                throw Error(ErrorCode::InvalidArgument, fileName_ + ": the column mapping must name x, y and z");
            return m;
        }
        for (auto it = headerLines.rbegin(); it != headerLines.rend(); ++it) {
            std::string_view line = trim(*it);
            if (line.substr(0, 2) == "//")
                line.remove_prefix(2);
            else if (line.substr(0, 1) == "#")
                line.remove_prefix(1);
            std::vector<std::string_view> names;
            splitter.split(line, names);
            if (names.size() != columnCount_)
                splitAny(line, names);
            if (names.size() != columnCount_)
                continue;
            Mapping m;
            for (std::string_view name : names)
                m.addNamed(name);
            if (m.hasXyz())
                return m;
        }
        return mappingByCount(columnCount_, sampleColumns(splitter), pts_);
    }

    std::vector<ColumnStats> sampleColumns(const Splitter& splitter)
    {
        std::vector<ColumnStats> stats(columnCount_);
        LineCursor cursor = cursor_;
        std::string_view line = firstRow_;
        std::vector<std::string_view> tokens;
        for (std::size_t row = 0; row < kSampleRows; ++row) {
            splitter.split(line, tokens);
            if (tokens.size() == columnCount_) {
                for (std::size_t c = 0; c < columnCount_; ++c) {
                    double v;
                    if (!parseDouble(tokens[c], v)) {
                        // Let the real parse report the bad value with its line.
                        stats[c].colorIntegers = stats[c].unit = false;
                        continue;
                    }
                    stats[c].colorIntegers = stats[c].colorIntegers && v >= 0 && v <= 255 && v == std::floor(v);
                    stats[c].aboveOne = stats[c].aboveOne || v > 1;
                    stats[c].unit = stats[c].unit && std::abs(v) <= 1.0 + 1e-6;
                }
            }
            bool found = false;
            while (cursor.next(line)) {
                const std::string_view t = trim(line);
                if (!t.empty() && !isCommentLine(t)) {
                    found = true;
                    break;
                }
            }
            if (!found)
                break;
        }
        return stats;
    }

    void parseRows(const Splitter& splitter, ProgressTicker& ticker)
    {
        // Guess the point count from the first row's length to avoid regrowing.
        const std::size_t estimate = file_.size() / std::max<std::size_t>(firstRow_.size() + 1, 8) + 16;
        xyz_.reserve(3 * estimate);
        hasColors_ = mapping_.hasColors();
        hasNormals_ = mapping_.hasNormals();
        if (hasColors_)
            colors_.reserve(estimate);
        if (hasNormals_)
            normals_.reserve(estimate);
        fields_.assign(mapping_.fieldNames.size(), {});
        for (auto& f : fields_)
            f.reserve(estimate);
        offsets_.assign(mapping_.fieldNames.size(), std::numeric_limits<double>::quiet_NaN());
        exact_.assign(mapping_.fieldNames.size(), {});
        exactSince_.assign(mapping_.fieldNames.size(), false);

        std::vector<std::string_view> tokens;
        std::string_view line = firstRow_;
        std::size_t lineNumber = firstRowLine_;
        LineCursor cursor = dataStart_;
        std::size_t rows = 0;
        std::size_t lastOffset = 0;
        while (true) {
            splitter.split(line, tokens);
            const bool ptsCount = pts_ && tokens.size() == 1 && isInteger(tokens[0]);
            if (!ptsCount) {
                if (tokens.size() != columnCount_)
                    failAtLine(lineNumber, "expected " + std::to_string(columnCount_) + " values, found " +
                                               std::to_string(tokens.size()));
                parseRow(tokens, lineNumber);
            }
            if (++rows % kRowsPerStep == 0) {
                ticker.step(cursor.offset() - lastOffset);
                lastOffset = cursor.offset();
            }
            bool found = false;
            while (cursor.next(line)) {
                const std::string_view t = trim(line);
                if (!t.empty() && !isCommentLine(t)) {
                    found = true;
                    break;
                }
            }
            if (!found)
                break;
            lineNumber = cursor.lineNumber();
        }
        ticker.step(cursor.offset() - lastOffset);
        if (xyz_.empty())
            fail("no data row");
    }

    void parseRow(const std::vector<std::string_view>& tokens, std::size_t lineNumber)
    {
        double xyz[3] = {0, 0, 0};
        Rgb8 rgb;
        Eigen::Vector3f normal = Eigen::Vector3f::Zero();
        for (std::size_t c = 0; c < columnCount_; ++c) {
            const Column& column = mapping_.columns[c];
            if (column.role == Role::Skip)
                continue;
            double v = 0.0;
            if (!parseDouble(tokens[c], v))
                failAtLine(lineNumber, "column " + std::to_string(c + 1) + ": " + quoted(tokens[c]) + " is not a number");
            switch (column.role) {
            case Role::X: xyz[0] = v; break;
            case Role::Y: xyz[1] = v; break;
            case Role::Z: xyz[2] = v; break;
            case Role::Red: rgb.r = colourByte(v, column.colorScale); break;
            case Role::Green: rgb.g = colourByte(v, column.colorScale); break;
            case Role::Blue: rgb.b = colourByte(v, column.colorScale); break;
            case Role::Nx: normal.x() = static_cast<float>(v); break;
            case Role::Ny: normal.y() = static_cast<float>(v); break;
            case Role::Nz: normal.z() = static_cast<float>(v); break;
            case Role::Field: {
                double& offset = offsets_[column.field];
                if (std::isnan(offset) && !std::isnan(v))
                    offset = chooseFieldOffset(v);
                const double base = std::isnan(offset) ? 0.0 : offset;
                std::vector<float>& floats = fields_[column.field];
                std::vector<double>& exact = exact_[column.field];
                const bool keeping = exactSince_[column.field];
                if (!keeping && !std::isnan(v) && !floatKeeps(tokens[c], v, base)) {
                    // The first value a float cannot give back: from here on the
                    // field keeps doubles, the earlier values being exact in float.
                    exactSince_[column.field] = true;
                    exact.reserve(floats.capacity());
                    for (float earlier : floats)
                        exact.push_back(base + static_cast<double>(earlier));
                }
                floats.push_back(static_cast<float>(v - base));
                if (exactSince_[column.field])
                    exact.push_back(v);
                break;
            }
            case Role::Skip: break;
            }
        }
        xyz_.insert(xyz_.end(), xyz, xyz + 3);
        if (hasColors_)
            colors_.push_back(rgb);
        if (hasNormals_)
            normals_.push_back(normal);
    }

    PointCloud buildCloud()
    {
        const std::size_t n = xyz_.size() / 3;
        Eigen::Vector3d origin = Eigen::Vector3d::Zero();
        if (options_.origin) {
            origin = *options_.origin;
        } else {
            BoundingBox box;
            Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
            Eigen::Vector3d hi = -lo;
            for (std::size_t i = 0; i < n; ++i) {
                const Eigen::Vector3d p(xyz_[3 * i], xyz_[3 * i + 1], xyz_[3 * i + 2]);
                if (!p.allFinite())
                    continue;
                lo = lo.cwiseMin(p);
                hi = hi.cwiseMax(p);
                box.empty = false;
            }
            box.min = lo;
            box.max = hi;
            origin = suggestOrigin(box);
        }
        PointCloud cloud;
        cloud.resize(n);
        cloud.setOrigin(origin);
        auto& positions = cloud.positions();
        for (std::size_t i = 0; i < n; ++i)
            for (int a = 0; a < 3; ++a)
                positions[i][a] = static_cast<float>(xyz_[3 * i + static_cast<std::size_t>(a)] - origin[a]);
        xyz_ = {};
        if (hasColors_)
            cloud.enableColors() = std::move(colors_);
        if (hasNormals_)
            cloud.enableNormals() = std::move(normals_);
        for (std::size_t f = 0; f < fields_.size(); ++f) {
            ScalarField field(mapping_.fieldNames[f]);
            field.values() = std::move(fields_[f]);
            field.setOffset(std::isnan(offsets_[f]) ? 0.0 : offsets_[f]);
            if (exactSince_[f]) {
                field.keepDoubles();
                field.doubles().swap(exact_[f]);
                exact_[f] = {};
                field.compact();
            }
            cloud.addField(std::move(field));
        }
        if (const std::size_t dropped = cloud.removeNonFinitePoints(); dropped > 0)
            logWarning(fileName_ + ": " + std::to_string(dropped) + " points with non-finite coordinates were skipped");
        return cloud;
    }

    fs::path path_;
    std::string fileName_;
    const ReadOptions& options_;
    MappedFile file_;
    LineCursor cursor_;
    LineCursor dataStart_{nullptr, nullptr};
    std::string_view firstRow_;
    std::size_t firstRowLine_ = 0;
    std::size_t columnCount_ = 0;
    bool pts_ = false;
    Mapping mapping_;
    bool hasColors_ = false;
    bool hasNormals_ = false;
    std::vector<std::string_view> scratch_;

    std::vector<double> xyz_;
    std::vector<Rgb8> colors_;
    std::vector<Eigen::Vector3f> normals_;
    std::vector<std::vector<float>> fields_;
    std::vector<double> offsets_; //!< NaN until the field's first value is seen
    //! Per field, empty until a value that a float cannot give back is read.
    std::vector<std::vector<double>> exact_;
    std::vector<bool> exactSince_; //!< per field: a value needed its double
};

// ---------------------------------------------------------------- writing

//! A header name the reader maps back to this field.
std::string headerName(const std::string& fieldName)
{
    std::string name = fieldName.empty() ? std::string("field") : fieldName;
    for (char& c : name)
        if (static_cast<unsigned char>(c) <= 32 || c == ',' || c == ';' || static_cast<unsigned char>(c) == 127)
            c = '_';
    static const char* reserved[] = {"x",  "y",  "z",  "r",  "g",  "b",  "red", "green", "blue",
                                     "rf", "gf", "bf", "nx", "ny", "nz", "skip"};
    const std::string key = lower(name);
    if (std::any_of(std::begin(reserved), std::end(reserved), [&](const char* r) { return key == r; }))
        name += "_sf";
    return name;
}

class NumberWriter
{
public:
    void fixed(std::string& out, double v, int precision)
    {
        if (!std::isfinite(v))
            return special(out, v);
        const auto r = std::to_chars(buffer_, buffer_ + sizeof(buffer_), v, std::chars_format::fixed, precision);
        if (r.ec == std::errc())
            out.append(buffer_, r.ptr);
        else
            shortest(out, v);
    }
    template <typename T>
    void shortest(std::string& out, T v)
    {
        if constexpr (std::is_floating_point_v<T>)
            if (!std::isfinite(v))
                return special(out, static_cast<double>(v));
        const auto r = std::to_chars(buffer_, buffer_ + sizeof(buffer_), v);
        out.append(buffer_, r.ptr);
    }

private:
    static void special(std::string& out, double v)
    {
        // Always "nan": to_chars may write "-nan", which other tools reject.
        out += std::isnan(v) ? "nan" : v > 0 ? "inf" : "-inf";
    }
    char buffer_[512];
};

void writeAsciiCloud(const PointCloud& cloud, const fs::path& path, const WriteOptions& options)
{
    if (options.encoding != Encoding::Default && options.encoding != Encoding::Ascii)
        throw Error(ErrorCode::InvalidArgument, path.string() + ": ASCII point files have no binary encoding");
    const int precision = std::clamp(options.asciiPrecision, 0, 17);
    const char sep = lowerExtension(path) == "csv" ? ',' : ' ';

    AtomicFile file(path);
    std::ofstream& out = file.stream();
    std::string text = "//X";
    text += sep;
    text += 'Y';
    text += sep;
    text += 'Z';
    auto addName = [&](const std::string& name) {
        text += sep;
        text += name;
    };
    if (cloud.hasColors())
        for (const char* name : {"R", "G", "B"})
            addName(name);
    if (cloud.hasNormals())
        for (const char* name : {"Nx", "Ny", "Nz"})
            addName(name);
    for (const auto& field : cloud.fields())
        addName(headerName(field.name()));
    text += '\n';

    const std::size_t n = cloud.size();
    ProgressTicker ticker(options.progress, "Writing " + path.filename().string(), n);
    NumberWriter number;
    const Eigen::Vector3d& origin = cloud.origin();
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Vector3f& p = cloud.positions()[i];
        for (int a = 0; a < 3; ++a) {
            if (a > 0)
                text += sep;
            number.fixed(text, origin[a] + static_cast<double>(p[a]), precision);
        }
        if (cloud.hasColors()) {
            const Rgb8& c = cloud.colors()[i];
            for (int channel : {c.r, c.g, c.b}) {
                text += sep;
                number.shortest(text, channel);
            }
        }
        if (cloud.hasNormals())
            for (int a = 0; a < 3; ++a) {
                text += sep;
                number.shortest(text, cloud.normals()[i][a]);
            }
        for (const auto& field : cloud.fields()) {
            text += sep;
            // A float field prints exactly in its shortest float form; with an
            // offset the sum needs double digits.
            if (field.offset() == 0.0 && !field.isDouble())
                number.shortest(text, field.values()[i]);
            else
                number.shortest(text, field.value(i));
        }
        text += '\n';
        if (text.size() > (1u << 20)) {
            out.write(text.data(), static_cast<std::streamsize>(text.size()));
            text.clear();
        }
        if ((i + 1) % kRowsPerStep == 0)
            ticker.step(kRowsPerStep);
    }
    ticker.step(n % kRowsPerStep);
    out.write(text.data(), static_cast<std::streamsize>(text.size()));
    file.commit();
}

} // namespace

FormatHandler asciiFormat()
{
    FormatHandler handler;
    handler.name = "ASCII";
    handler.extensions = {"xyz", "txt", "csv", "pts", "asc", "neu"};
    handler.read = [](const fs::path& path, const ReadOptions& options) -> Entity {
        return AsciiReader(path, options).read();
    };
    handler.writeCloud = writeAsciiCloud;
    return handler;
}

} // namespace scandiff::io::detail
