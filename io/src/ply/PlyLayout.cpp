// SPDX-License-Identifier: GPL-3.0-or-later
//! The vertex layout of a PLY element (ply/PlyLayout.h).

#include "ply/PlyLayout.h"

#include <algorithm>
#include <unordered_map>
#include <unordered_set>

namespace scandiff::io::detail::ply {

VertexLayout makeVertexLayout(const PlyElement& e, const Context& ctx)
{
    VertexLayout layout;
    layout.slotOfProperty.assign(e.properties.size(), -1);
    bool hasAxis[3] = {false, false, false};
    std::unordered_set<std::string> usedNames;          // the field names so far
    std::unordered_map<std::string, int> nextSuffix;    // per base name, the next "_k" to try
    std::size_t offset = 0;
    for (std::size_t i = 0; i < e.properties.size(); ++i) {
        const PlyProperty& p = e.properties[i];
        const std::size_t size = typeSize(p.isList ? p.countType : p.type);
        const std::size_t propertyOffset = offset;
        offset += size;
        if (p.isList)
            continue;
        const std::string name = lower(p.name);
        Slot slot;
        slot.type = p.type;
        slot.offset = propertyOffset;
        if (name == "x" || name == "y" || name == "z") {
            const int axis = name[0] - 'x';
            slot.role = static_cast<Role>(static_cast<int>(Role::X) + axis);
            hasAxis[axis] = true;
            if (p.type == PlyType::Float64)
                layout.coordinatesAreDouble = true;
        } else if (name == "red" || name == "diffuse_red" || name == "green" || name == "diffuse_green" ||
                   name == "blue" || name == "diffuse_blue") {
            const std::string base = name.rfind("diffuse_", 0) == 0 ? name.substr(8) : name;
            slot.role = base == "red" ? Role::Red : base == "green" ? Role::Green : Role::Blue;
            if (isFloatType(p.type))
                slot.colorScale = 255.0;
            else if (p.type == PlyType::UInt16 || p.type == PlyType::Int16)
                slot.colorScale = 255.0 / 65535.0;
            layout.hasColors = true;
        } else if (name == "alpha" || name == "diffuse_alpha") {
            continue;
        } else if (name == "nx" || name == "ny" || name == "nz" || name == "normal_x" || name == "normal_y" ||
                   name == "normal_z") {
            const int axis = name.back() - 'x';
            slot.role = static_cast<Role>(static_cast<int>(Role::Nx) + axis);
            layout.hasNormals = true;
        } else {
            std::string fieldName = p.name;
            if (name.rfind("scalar_", 0) == 0 && fieldName.size() > 7)
                fieldName.erase(0, 7);
            // Two properties may map to one name ("scalar_a" and "a"): keep
            // both. In constant time per property: a hostile header repeating
            // one name thousands of times took 44 s with a search per suffix.
            const std::string base = fieldName;
            int& next = nextSuffix[base];
            next = std::max(next, 2);
            while (usedNames.count(fieldName) != 0)
                fieldName = base + "_" + std::to_string(next++);
            usedNames.insert(fieldName);
            slot.role = Role::Field;
            slot.field = static_cast<std::uint32_t>(layout.fieldNames.size());
            layout.fieldNames.push_back(fieldName);
            layout.fieldIsWide.push_back(p.type == PlyType::Float64 || p.type == PlyType::Int32 ||
                                         p.type == PlyType::UInt32);
        }
        slot.index = static_cast<std::uint32_t>(layout.slots.size());
        layout.slotOfProperty[i] = static_cast<int>(slot.index);
        layout.slots.push_back(slot);
    }
    if (!hasAxis[0] || !hasAxis[1] || !hasAxis[2])
        ctx.fail("the " + e.name + " element has no x, y and z properties");
    return layout;
}

//! Keeps the slots `keep` accepts, renumbered, and the map from properties
//! to slots with them (records of variable size are visited through it).
template <class Keep>
void keepSlots(VertexLayout& layout, Keep&& keep)
{
    std::vector<int> newIndex(layout.slots.size(), -1);
    std::vector<Slot> kept;
    for (const Slot& s : layout.slots)
        if (keep(s)) {
            newIndex[s.index] = static_cast<int>(kept.size());
            kept.push_back(s);
            kept.back().index = static_cast<std::uint32_t>(newIndex[s.index]);
        }
    for (int& slot : layout.slotOfProperty)
        if (slot >= 0)
            slot = newIndex[static_cast<std::size_t>(slot)];
    layout.slots = std::move(kept);
    layout.fieldNames.clear();
    layout.fieldIsWide.clear();
    layout.hasColors = false;
}


//! Drops colours and scalar fields from a layout (ReadOptions::geometryOnly):
//! their values are then never decoded.
void keepGeometryOnly(VertexLayout& layout)
{
    keepSlots(layout, [](const Slot& s) { return isCoordinate(s) || (s.role >= Role::Nx && s.role <= Role::Nz); });
}

//! The layout's x, y and z alone (the passes over coordinates).
VertexLayout coordinatesOnly(const VertexLayout& layout)
{
    VertexLayout coordinates = layout;
    keepSlots(coordinates, isCoordinate);
    coordinates.hasNormals = false;
    return coordinates;
}

} // namespace scandiff::io::detail::ply
