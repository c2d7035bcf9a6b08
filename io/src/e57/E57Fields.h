// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! Names shared by the E57 reader and writer: which record fields of the
//! standard become which scalar fields, and how scandiff's own fields travel
//! in an extension namespace so that a round trip keeps every one.

#include "e57/E57Tree.h"

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace scandiff::io::e57 {

//! The namespace (and prefix) of the scalar fields the standard has no element for.
inline constexpr std::string_view kScalarFieldNamespace = "urn:scandiff:e57:scalar-fields";
inline constexpr std::string_view kScalarFieldPrefix = "sdf";
inline constexpr std::string_view kNormalsPrefix = "nor";

//! The scalar field a record field becomes: "intensity", "time_stamp",
//! "row_index"... for the standard's, the decoded name for scandiff's own,
//! "prefix_name" for another extension's.
std::string fieldNameFor(const Node& field);
//! The standard element a scalar field is written as ("timeStamp"), if it has one.
std::optional<std::string> standardElementFor(const std::string& fieldName);
//! A field name as an XML name (characters XML names cannot hold as _xHH_) and back.
std::string encodeXmlName(const std::string& name);
std::string decodeXmlName(const std::string& name);

//! A file name made from an image's name (no folder separators or control characters).
std::string safeFileStem(const std::string& name);
//! Writes bytes through a temporary file renamed into place.
void writeBytesAtomically(const std::filesystem::path& path, const std::vector<char>& bytes);

} // namespace scandiff::io::e57
