// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Comma-separated lists as users type them in options and dialogs
//! ("512000,5403000,0", "x,y,z,intensity").

#include <string>
#include <vector>

namespace scandiff {

//! Splits on `separator`; empty parts are kept ("a,,b" gives three parts).
std::vector<std::string> splitList(const std::string& text, char separator);

//! "1.5,2,-3" -> {1.5, 2, -3}. Throws Error(InvalidArgument) naming `what`
//! when a part is not a finite number.
std::vector<double> parseNumberList(const std::string& text, const std::string& what);

//! Numbers between commas, semicolons or blanks, as a range is typed in a
//! dialog ("0.1 0.5"), on the command line (its values joined by ';') or in a
//! list ("0.1,0.5"). Throws as parseNumberList does.
std::vector<double> parseNumberWords(const std::string& text, const std::string& what);

} // namespace scandiff
