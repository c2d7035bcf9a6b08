// SPDX-License-Identifier: GPL-3.0-or-later
// Debian's expat parses the XML section: a small, hardened parser (it never
// loads an external entity unless asked to; a section declaring any entity
// is refused here, E57 files declare none). It replaced xerces-c, whose library
// and its dependencies took 21 ms of every process's start, E57 or not.
#include "e57/E57Tree.h"

#include <scandiff/core/Error.h>

#include <expat.h>

#include <algorithm>
#include <charconv>
#include <memory>
#include <new>
#include <type_traits>

namespace scandiff::io::e57 {

namespace {

// E57 files nest a handful of levels (root, data3D, scan, points, prototype,
// field); 64 leaves room for extensions and keeps a hostile file's tree small.
constexpr int kMaxDepth = 64;

//! Separates the namespace URI, local name and prefix of the names expat
//! reports (XML_ParserCreateNS with triplets); a character no URI or XML name holds.
constexpr char kNameSeparator = '\x01';

std::string trimmed(std::string s)
{
    const auto first = s.find_first_not_of(" \t\r\n");
    if (first == std::string::npos)
        return {};
    const auto last = s.find_last_not_of(" \t\r\n");
    return s.substr(first, last - first + 1);
}

//! "uri\x01local\x01prefix", "uri\x01local" or "local" into the node's names.
void splitName(const char* expanded, Node& node)
{
    const std::string_view name(expanded);
    const auto first = name.find(kNameSeparator);
    if (first == std::string_view::npos) {
        node.localName = name;
        return;
    }
    node.namespaceUri = name.substr(0, first);
    const auto second = name.find(kNameSeparator, first + 1);
    node.localName = name.substr(first + 1, second == std::string_view::npos ? std::string_view::npos : second - first - 1);
    if (second != std::string_view::npos)
        node.prefix = name.substr(second + 1);
}

//! Builds the tree from expat's events: the open elements on a stack, each
//! closed one moved into its parent.
struct TreeBuilder
{
    XML_Parser parser = nullptr;
    std::vector<Node> open;
    std::vector<std::string> text; //!< character data of each open element
    Node root;
    bool hasRoot = false;
    std::string error; //!< set when the builder stops the parse

    void stop(std::string why)
    {
        error = std::move(why);
        XML_StopParser(parser, XML_FALSE);
    }

    static void onStart(void* data, const XML_Char* name, const XML_Char** attributes)
    {
        auto& self = *static_cast<TreeBuilder*>(data);
        if (static_cast<int>(self.open.size()) > kMaxDepth)
            return self.stop("the XML section nests deeper than " + std::to_string(kMaxDepth) + " levels");
        Node node;
        splitName(name, node);
        // Namespace declarations are consumed by expat; attribute names without a namespace stay as written.
        for (const XML_Char** a = attributes; a && a[0]; a += 2) {
            Node attribute;
            splitName(a[0], attribute);
            const std::string key = attribute.prefix.empty() ? attribute.localName : attribute.prefix + ":" + attribute.localName;
            if (key == "type")
                node.type = a[1];
            else
                node.attributes.emplace_back(key, a[1]);
        }
        self.open.push_back(std::move(node));
        self.text.emplace_back();
    }

    static void onEnd(void* data, const XML_Char*)
    {
        auto& self = *static_cast<TreeBuilder*>(data);
        // expat may still report the end of an element whose start stopped the parse.
        if (self.open.empty() || !self.error.empty())
            return;
        Node node = std::move(self.open.back());
        std::string text = std::move(self.text.back());
        self.open.pop_back();
        self.text.pop_back();
        // Strings keep their spaces; numbers are trimmed.
        node.text = node.type == "String" ? std::move(text) : trimmed(std::move(text));
        if (!self.open.empty()) {
            self.open.back().children.push_back(std::move(node));
        } else {
            self.root = std::move(node);
            self.hasRoot = true;
        }
    }

    //! E57 files declare no entity: a section that does is refused before any
    //! expansion (the "billion laughs" and external-entity attacks start so).
    static void onEntity(void* data, const XML_Char* name, int, const XML_Char*, int, const XML_Char*, const XML_Char*, const XML_Char*,
                         const XML_Char*)
    {
        static_cast<TreeBuilder*>(data)->stop(std::string("the XML section declares the entity '") + name +
                                              "', which E57 files never do");
    }

    static void onText(void* data, const XML_Char* s, int length)
    {
        auto& self = *static_cast<TreeBuilder*>(data);
        if (!self.text.empty())
            self.text.back().append(s, static_cast<std::size_t>(length));
    }
};

[[noreturn]] void badNumber(const Node& node, const std::string& context, const std::string& text)
{
    throw Error(ErrorCode::InvalidData, context + ": the XML element '" + node.qualifiedName() + "' (" + node.type +
                                            ") holds '" + text.substr(0, 40) + "', which is not a number");
}

std::int64_t parseInteger(const std::string& text, const Node& node, const std::string& context)
{
    std::int64_t value = 0;
    const char* end = text.data() + text.size();
    const auto [ptr, ec] = std::from_chars(text.data(), end, value);
    if (ec != std::errc() || ptr != end)
        badNumber(node, context, text);
    return value;
}

double parseFloat(const std::string& text, const Node& node, const std::string& context)
{
    double value = 0;
    const char* begin = text.data();
    const char* end = text.data() + text.size();
    if (begin != end && *begin == '+')
        ++begin;
    const auto [ptr, ec] = std::from_chars(begin, end, value);
    // Out of range ("1e999") saturates as strtod would; anything else is an error.
    if ((ec != std::errc() && ec != std::errc::result_out_of_range) || ptr != end)
        badNumber(node, context, text);
    return value;
}

} // namespace

const Node* Node::child(std::string_view name) const
{
    return child(name, kE57Namespace);
}

const Node* Node::child(std::string_view name, std::string_view uri) const
{
    for (const Node& c : children)
        if (c.localName == name && c.namespaceUri == uri)
            return &c;
    return nullptr;
}

const std::string* Node::attribute(std::string_view name) const
{
    for (const auto& [key, value] : attributes)
        if (key == name)
            return &value;
    return nullptr;
}

Node parseTree(const std::vector<char>& xml, const std::string& context)
{
    const std::unique_ptr<std::remove_pointer_t<XML_Parser>, decltype(&XML_ParserFree)> parser(
        XML_ParserCreateNS(nullptr, kNameSeparator), &XML_ParserFree);
    if (!parser)
        throw std::bad_alloc();
    XML_SetReturnNSTriplet(parser.get(), 1);
    TreeBuilder builder;
    builder.parser = parser.get();
    XML_SetUserData(parser.get(), &builder);
    XML_SetElementHandler(parser.get(), &TreeBuilder::onStart, &TreeBuilder::onEnd);
    XML_SetCharacterDataHandler(parser.get(), &TreeBuilder::onText);
    XML_SetEntityDeclHandler(parser.get(), &TreeBuilder::onEntity);
    // Fed in pieces: XML_Parse takes an int length, and copies each piece into
    // a buffer it grows by doubling an int (pieces of 1 GiB overflowed it).
    constexpr std::size_t kPiece = std::size_t(32) << 20;
    std::size_t at = 0;
    XML_Status status = XML_STATUS_OK;
    do {
        const std::size_t length = std::min(kPiece, xml.size() - at);
        const bool last = at + length == xml.size();
        status = XML_Parse(parser.get(), xml.data() + at, static_cast<int>(length), last ? XML_TRUE : XML_FALSE);
        at += length;
    } while (status == XML_STATUS_OK && at < xml.size());
    if (!builder.error.empty())
        throw Error(ErrorCode::InvalidData, context + ": " + builder.error);
    if (status != XML_STATUS_OK)
        throw Error(ErrorCode::InvalidData, context + ": the XML section is malformed (line " +
                                                std::to_string(XML_GetCurrentLineNumber(parser.get())) + ", column " +
                                                std::to_string(XML_GetCurrentColumnNumber(parser.get()) + 1) +
                                                "): " + XML_ErrorString(XML_GetErrorCode(parser.get())));
    if (!builder.hasRoot)
        throw Error(ErrorCode::InvalidData, context + ": the XML section holds no element");
    Node tree = std::move(builder.root);
    if (tree.localName != "e57Root" || tree.type != "Structure")
        throw Error(ErrorCode::InvalidData, context + ": the XML section's root is '" + tree.qualifiedName() +
                                                "', not an E57 root structure");
    return tree;
}

std::int64_t integerValue(const Node& node, const std::string& context)
{
    if (node.type != "Integer" && node.type != "ScaledInteger")
        throw Error(ErrorCode::InvalidData, context + ": the XML element '" + node.qualifiedName() + "' should be an Integer, not '" +
                                                node.type + "'");
    return node.text.empty() ? 0 : parseInteger(node.text, node, context);
}

double floatValue(const Node& node, const std::string& context)
{
    if (node.type == "Integer")
        return static_cast<double>(integerValue(node, context));
    if (node.type == "ScaledInteger") {
        const double scale = floatAttribute(node, "scale", 1.0, context), offset = floatAttribute(node, "offset", 0.0, context);
        return static_cast<double>(integerValue(node, context)) * scale + offset;
    }
    if (node.type != "Float")
        throw Error(ErrorCode::InvalidData, context + ": the XML element '" + node.qualifiedName() + "' should be a number, not '" +
                                                node.type + "'");
    return node.text.empty() ? 0.0 : parseFloat(node.text, node, context);
}

double numberOr(const Node* parent, std::string_view name, double fallback, const std::string& context)
{
    const Node* node = parent ? parent->child(name) : nullptr;
    return node ? floatValue(*node, context) : fallback;
}

std::string stringOr(const Node* parent, std::string_view name, std::string fallback)
{
    const Node* node = parent ? parent->child(name) : nullptr;
    return node && node->type == "String" ? node->text : std::move(fallback);
}

std::int64_t integerAttribute(const Node& node, std::string_view name, std::int64_t fallback, const std::string& context)
{
    const std::string* text = node.attribute(name);
    return text ? parseInteger(trimmed(*text), node, context) : fallback;
}

double floatAttribute(const Node& node, std::string_view name, double fallback, const std::string& context)
{
    const std::string* text = node.attribute(name);
    return text ? parseFloat(trimmed(*text), node, context) : fallback;
}

} // namespace scandiff::io::e57
