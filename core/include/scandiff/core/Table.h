// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! A small table of results (a histogram, fitted primitive parameters, a
//! per-region report): named columns, rows of numbers or text. Tools return it;
//! the CLI writes it as CSV, the workbench shows it and saves it.

#include <string>
#include <variant>
#include <vector>

namespace scandiff {

using TableCell = std::variant<double, std::string>;

struct Table
{
    std::vector<std::string> columns;
    std::vector<std::vector<TableCell>> rows;
    //! Written as lines of numbers separated by spaces, without the header (a
    //! file of poses, 16 numbers a line), with the extension .txt.
    bool plainNumbers = false;

    //! Comma-separated, a header line then one line per row; numbers in the
    //! shortest text that reads back to the same double (NaN as "nan"); text
    //! quoted when it holds a comma, a quote or a line break (RFC 4180).
    std::string toCsv() const;
    //! The text of the table's file: toCsv(), or the plain numbers.
    std::string toText() const;
};

} // namespace scandiff
