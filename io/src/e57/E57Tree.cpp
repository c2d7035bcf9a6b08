// SPDX-License-Identifier: GPL-3.0-or-later
// Debian's xerces-c parses the XML section: the E57 reference implementation
// uses it too, and it is a validating parser hardened against hostile input,
// which a hand-written one would not be.
#include "e57/E57Tree.h"

#include <scandiff/core/Error.h>

#include <xercesc/dom/DOM.hpp>
#include <xercesc/framework/MemBufInputSource.hpp>
#include <xercesc/parsers/XercesDOMParser.hpp>
#include <xercesc/sax/HandlerBase.hpp>
#include <xercesc/util/PlatformUtils.hpp>
#include <xercesc/util/SecurityManager.hpp>
#include <xercesc/util/TransService.hpp>
#include <xercesc/util/XMLString.hpp>

#include <charconv>
#include <memory>
#include <mutex>

namespace scandiff::io::e57 {

namespace x = XERCES_CPP_NAMESPACE;

namespace {

// E57 files nest a handful of levels (root, data3D, scan, points, prototype,
// field); 64 leaves room for extensions and stops a hostile file from
// exhausting the stack of the recursive copy.
constexpr int kMaxDepth = 64;

void initialiseXerces()
{
    // Initialise() is not thread-safe; Terminate() is never called because
    // other threads may still parse (the process exit frees everything).
    static std::once_flag once;
    std::call_once(once, [] { x::XMLPlatformUtils::Initialize(); });
}

std::string utf8(const XMLCh* text)
{
    if (!text)
        return {};
    x::TranscodeToStr converted(text, "UTF-8");
    return std::string(reinterpret_cast<const char*>(converted.str()), converted.length());
}

std::string trimmed(std::string s)
{
    const auto first = s.find_first_not_of(" \t\r\n");
    if (first == std::string::npos)
        return {};
    const auto last = s.find_last_not_of(" \t\r\n");
    return s.substr(first, last - first + 1);
}

class ThrowingErrors : public x::HandlerBase
{
public:
    void error(const x::SAXParseException& e) override { throw e; }
    void fatalError(const x::SAXParseException& e) override { throw e; }
    void warning(const x::SAXParseException&) override {}
};

Node copyElement(const x::DOMElement& element, int depth, const std::string& context)
{
    if (depth > kMaxDepth)
        throw Error(ErrorCode::InvalidData, context + ": the XML section nests deeper than " + std::to_string(kMaxDepth) + " levels");
    Node node;
    node.localName = utf8(element.getLocalName());
    node.namespaceUri = utf8(element.getNamespaceURI());
    node.prefix = utf8(element.getPrefix());
    const x::DOMNamedNodeMap* attributes = element.getAttributes();
    for (XMLSize_t i = 0; attributes && i < attributes->getLength(); ++i) {
        const x::DOMNode* a = attributes->item(i);
        std::string name = utf8(a->getNodeName());
        if (name == "type")
            node.type = utf8(a->getNodeValue());
        else if (name.rfind("xmlns", 0) != 0)
            node.attributes.emplace_back(std::move(name), utf8(a->getNodeValue()));
    }
    std::string text;
    for (const x::DOMNode* c = element.getFirstChild(); c; c = c->getNextSibling()) {
        const auto kind = c->getNodeType();
        if (kind == x::DOMNode::ELEMENT_NODE)
            node.children.push_back(copyElement(static_cast<const x::DOMElement&>(*c), depth + 1, context));
        else if (kind == x::DOMNode::TEXT_NODE || kind == x::DOMNode::CDATA_SECTION_NODE)
            text += utf8(c->getNodeValue());
    }
    // Strings keep their spaces; numbers are trimmed.
    node.text = node.type == "String" ? std::move(text) : trimmed(std::move(text));
    return node;
}

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
    initialiseXerces();
    x::XercesDOMParser parser;
    parser.setValidationScheme(x::XercesDOMParser::Val_Never);
    parser.setDoNamespaces(true);
    parser.setDoSchema(false);
    parser.setLoadExternalDTD(false);
    parser.setCreateEntityReferenceNodes(false);
    parser.setDisableDefaultEntityResolution(true);
    // Caps entity expansion: a "billion laughs" section stops with an error.
    x::SecurityManager security;
    security.setEntityExpansionLimit(1000);
    parser.setSecurityManager(&security);
    ThrowingErrors errors;
    parser.setErrorHandler(&errors);
    x::MemBufInputSource source(reinterpret_cast<const XMLByte*>(xml.data()), xml.size(), "e57-xml", false);
    try {
        parser.parse(source);
    } catch (const x::SAXParseException& e) {
        throw Error(ErrorCode::InvalidData, context + ": the XML section is malformed (line " +
                                                std::to_string(e.getLineNumber()) + ", column " +
                                                std::to_string(e.getColumnNumber()) + "): " + utf8(e.getMessage()));
    } catch (const x::XMLException& e) {
        throw Error(ErrorCode::InvalidData, context + ": the XML section is malformed: " + utf8(e.getMessage()));
    } catch (const x::DOMException& e) {
        throw Error(ErrorCode::InvalidData, context + ": the XML section is malformed: " + utf8(e.getMessage()));
    }
    const x::DOMDocument* document = parser.getDocument();
    const x::DOMElement* root = document ? document->getDocumentElement() : nullptr;
    if (!root)
        throw Error(ErrorCode::InvalidData, context + ": the XML section holds no element");
    Node tree = copyElement(*root, 0, context);
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
