// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/io/AtomicFile.h>
#include <scandiff/io/ResultFiles.h>

#include <charconv>

namespace scandiff::io {

namespace {

void writeText(const std::string& text, const std::filesystem::path& path)
{
    AtomicFile file(path);
    file.stream() << text;
    file.commit();
}

} // namespace

void writeTable(const Table& table, const std::filesystem::path& path)
{
    writeText(table.toText(), path);
}

std::string matrixText(const Eigen::Matrix4d& matrix)
{
    std::string text;
    for (int r = 0; r < 4; ++r) {
        for (int c = 0; c < 4; ++c) {
            char buffer[32];
            const auto result = std::to_chars(buffer, buffer + sizeof buffer, matrix(r, c));
            text.append(buffer, result.ptr);
            text += c < 3 ? ' ' : '\n';
        }
    }
    return text;
}

void writeMatrix(const Eigen::Matrix4d& matrix, const std::filesystem::path& path)
{
    writeText(matrixText(matrix), path);
}

} // namespace scandiff::io
