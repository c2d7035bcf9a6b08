// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The XML section of an E57 file as a small tree of our own, so that expat
//! (which parses it) stays inside E57Tree.cpp. An E57 element is typed by its
//! `type` attribute: Structure, Vector, CompressedVector, Integer,
//! ScaledInteger, Float, String or Blob (ASTM E2807 §7).

#include <cstdint>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace scandiff::io::e57 {

//! The namespace of the standard's own elements, and of the normals extension CloudCompare and libE57Format write.
inline constexpr std::string_view kE57Namespace = "http://www.astm.org/COMMIT/E57/2010-e57-v1.0";
inline constexpr std::string_view kNormalsNamespace = "http://www.libe57.org/E57_NOR_surface_normals.txt";

struct Node
{
    std::string localName;  //!< "cartesianX"
    std::string namespaceUri; //!< kE57Namespace for the standard's elements
    std::string prefix;     //!< "nor" in "nor:normalX", empty for the default namespace
    std::string type;       //!< the `type` attribute
    std::vector<std::pair<std::string, std::string>> attributes; //!< all but `type`
    std::string text;       //!< character data, trimmed
    std::vector<Node> children;

    //! A standard child by name (in the E57 namespace), or null.
    const Node* child(std::string_view name) const;
    //! A child of any namespace by local name and namespace URI, or null.
    const Node* child(std::string_view name, std::string_view uri) const;
    //! The attribute's value, or null.
    const std::string* attribute(std::string_view name) const;
    //! "nor:normalX" or "cartesianX".
    std::string qualifiedName() const { return prefix.empty() ? localName : prefix + ":" + localName; }
};

//! Parses the XML section. Throws Error(InvalidData) prefixed by `context` (the file name) on malformed XML,
//! a root other than e57Root, or nesting deeper than E57 files use.
Node parseTree(const std::vector<char>& xml, const std::string& context);

//! Values of typed leaves; an empty element is 0 as the standard says. Throw Error(InvalidData) naming the
//! element when the text is not a number of the element's type.
std::int64_t integerValue(const Node& node, const std::string& context);
double floatValue(const Node& node, const std::string& context);
//! The numeric value of a child, or `fallback` when absent.
double numberOr(const Node* parent, std::string_view name, double fallback, const std::string& context);
std::string stringOr(const Node* parent, std::string_view name, std::string fallback = {});
//! Integer attribute (minimum, maximum, recordCount, fileOffset...); `fallback` when absent.
std::int64_t integerAttribute(const Node& node, std::string_view name, std::int64_t fallback, const std::string& context);
double floatAttribute(const Node& node, std::string_view name, double fallback, const std::string& context);

} // namespace scandiff::io::e57
