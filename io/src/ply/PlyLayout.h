// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The PLY reader's second step: where each property of the vertex element
//! goes (coordinates, colours, normals, scalar fields), the sink that writes
//! decoded values there, the ranges gathered before the offsets are chosen,
//! and the fan triangulation of faces.

#include "ply/PlyHeader.h"

#include <scandiff/core/Mesh.h>
#include <scandiff/core/PointCloud.h>

#include <Eigen/Core>

#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace scandiff::io::detail::ply {

enum class Role : std::uint8_t { Ignore, X, Y, Z, Red, Green, Blue, Nx, Ny, Nz, Field };

struct Slot
{
    Role role = Role::Ignore;
    PlyType type = PlyType::Float32;
    std::uint32_t index = 0;  //!< position in VertexLayout::slots
    std::uint32_t field = 0;  //!< index among the layout's fields for Role::Field
    std::size_t offset = 0;   //!< byte offset inside a fixed-size binary record
    double colorScale = 1.0;  //!< brings the stored colour to 0-255
};

struct VertexLayout
{
    std::vector<Slot> slots;          //!< the properties that carry data, in file order
    std::vector<int> slotOfProperty;  //!< per property of the element, -1 when skipped
    std::vector<std::string> fieldNames;
    //! Fields whose values may not fit a float around zero (double, 32-bit integers):
    //! their offset is chosen from their range before conversion.
    std::vector<bool> fieldIsWide;
    bool hasColors = false;
    bool hasNormals = false;
    bool coordinatesAreDouble = false;
};

//! The element's properties mapped to the cloud; fails when x, y or z is missing.
VertexLayout makeVertexLayout(const PlyElement& e, const Context& ctx);

inline bool isCoordinate(const Slot& s) { return s.role >= Role::X && s.role <= Role::Z; }

//! Drops colours and scalar fields from a layout (ReadOptions::geometryOnly):
//! their values are then never decoded.
void keepGeometryOnly(VertexLayout& layout);

//! The layout's x, y and z alone (the passes over coordinates).
VertexLayout coordinatesOnly(const VertexLayout& layout);

//! Where decoded vertex values go. Coordinates and wide fields go to double
//! staging buffers when their origin/offset can only be chosen after reading.
//! Set the members, call compile(), then put() every value.
struct VertexSink
{
    Eigen::Vector3f* positions = nullptr;
    Rgb8* colors = nullptr;
    Eigen::Vector3f* normals = nullptr;
    std::vector<float*> fieldValues;
    //! Per field, null unless the field keeps float residuals (its exact form),
    //! with a flag raised by a value they cannot give back.
    std::vector<float*> fieldResiduals;
    std::vector<std::atomic<bool>*> fieldResidualsFailed;
    std::vector<double> fieldOffsets;
    std::vector<double*> stagedFields; //!< per field, null when written directly
    double* stagedXyz = nullptr;
    Eigen::Vector3d origin = Eigen::Vector3d::Zero();

    //! Turns every slot into a strided destination, so that put() is a small
    //! switch the compiler inlines in the per-value loop.
    void compile(const VertexLayout& layout)
    {
        static_assert(sizeof(Eigen::Vector3f) == 3 * sizeof(float), "positions must be packed xyz floats");
        static_assert(sizeof(Rgb8) == 3, "colours must be packed rgb bytes");
        targets_.clear();
        // An empty element (`element vertex 0`) has no arrays: pointer
        // arithmetic on their null data would be undefined, and nothing is put.
        if (!positions && !stagedXyz)
            return;
        for (const Slot& s : layout.slots) {
            Target t;
            switch (s.role) {
            case Role::X:
            case Role::Y:
            case Role::Z: {
                const int axis = static_cast<int>(s.role) - static_cast<int>(Role::X);
                t.stride = 3;
                if (stagedXyz) {
                    t.kind = Target::Staged;
                    t.doubles = stagedXyz + axis;
                } else {
                    t.kind = Target::Float;
                    t.floats = reinterpret_cast<float*>(positions) + axis;
                    t.offset = origin[axis];
                }
                break;
            }
            case Role::Red:
            case Role::Green:
            case Role::Blue:
                t.kind = Target::Color;
                t.stride = 3;
                t.bytes = reinterpret_cast<std::uint8_t*>(colors) + (static_cast<int>(s.role) - static_cast<int>(Role::Red));
                t.colorScale = s.colorScale;
                break;
            case Role::Nx:
            case Role::Ny:
            case Role::Nz:
                t.kind = Target::Float;
                t.stride = 3;
                t.floats = reinterpret_cast<float*>(normals) + (static_cast<int>(s.role) - static_cast<int>(Role::Nx));
                break;
            case Role::Field:
                if (stagedFields[s.field]) {
                    t.kind = Target::Staged;
                    t.doubles = stagedFields[s.field];
                } else {
                    t.kind = fieldResiduals[s.field] ? Target::FloatAndResidual : Target::Float;
                    t.floats = fieldValues[s.field];
                    t.residuals = fieldResiduals[s.field];
                    t.failed = fieldResidualsFailed[s.field];
                    t.offset = fieldOffsets[s.field];
                }
                break;
            case Role::Ignore: break;
            }
            targets_.push_back(t);
        }
    }

    void put(std::size_t i, const Slot& s, double v) const
    {
        const Target& t = targets_[s.index];
        switch (t.kind) {
        case Target::Float: t.floats[i * t.stride] = static_cast<float>(v - t.offset); break;
        case Target::Color: t.bytes[i * t.stride] = colourByte(v, t.colorScale); break;
        case Target::Staged: t.doubles[i * t.stride] = v; break;
        case Target::FloatAndResidual: {
            const auto f = static_cast<float>(v - t.offset);
            t.floats[i] = f;
            t.residuals[i] = std::isnan(v) ? 0.0f : ScalarField::residualOf(v, t.offset, f);
            if (!ScalarField::residualHolds(v, t.offset))
                t.failed->store(true, std::memory_order_relaxed);
            break;
        }
        case Target::None: break;
        }
    }

private:
    struct Target
    {
        enum Kind : std::uint8_t { None, Float, Color, Staged, FloatAndResidual } kind = None;
        std::size_t stride = 1;
        float* floats = nullptr;
        std::uint8_t* bytes = nullptr;
        double* doubles = nullptr;
        float* residuals = nullptr;
        std::atomic<bool>* failed = nullptr;
        double offset = 0.0;
        double colorScale = 1.0;
    };
    std::vector<Target> targets_;
};


struct RangeAccumulator
{
    double lo[3] = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
                    std::numeric_limits<double>::infinity()};
    double hi[3] = {-std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                    -std::numeric_limits<double>::infinity()};
    std::vector<double> fieldLo, fieldHi;

    explicit RangeAccumulator(std::size_t fieldCount)
        : fieldLo(fieldCount, std::numeric_limits<double>::infinity()),
          fieldHi(fieldCount, -std::numeric_limits<double>::infinity())
    {
    }

    //! Each axis's range keeps its finite values only.
    void addCoordinate(int axis, double v)
    {
        if (std::isfinite(v)) {
            lo[axis] = std::min(lo[axis], v);
            hi[axis] = std::max(hi[axis], v);
        }
    }

    void add(const Slot& s, double v)
    {
        if (s.role >= Role::X && s.role <= Role::Z) {
            addCoordinate(static_cast<int>(s.role) - static_cast<int>(Role::X), v);
        } else if (s.role == Role::Field && std::isfinite(v)) {
            fieldLo[s.field] = std::min(fieldLo[s.field], v);
            fieldHi[s.field] = std::max(fieldHi[s.field], v);
        }
    }

    void merge(const RangeAccumulator& other)
    {
        for (int a = 0; a < 3; ++a) {
            lo[a] = std::min(lo[a], other.lo[a]);
            hi[a] = std::max(hi[a], other.hi[a]);
        }
        for (std::size_t f = 0; f < fieldLo.size(); ++f) {
            fieldLo[f] = std::min(fieldLo[f], other.fieldLo[f]);
            fieldHi[f] = std::max(fieldHi[f], other.fieldHi[f]);
        }
    }

    BoundingBox box() const
    {
        BoundingBox b;
        b.empty = !(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]);
        if (!b.empty) {
            b.min = Eigen::Vector3d(lo[0], lo[1], lo[2]);
            b.max = Eigen::Vector3d(hi[0], hi[1], hi[2]);
        }
        return b;
    }
};

//! Adds the fan triangulation of one polygon, checking every index.
class FaceBuilder
{
public:
    FaceBuilder(const PlyElement& faces, std::uint64_t vertexCount, const Context& ctx, std::vector<Triangle>& out)
        : faces_(faces), vertexCount_(vertexCount), ctx_(ctx), out_(out)
    {
    }

    void begin(std::uint64_t face)
    {
        face_ = face;
        corners_ = 0;
    }
    void add(std::int64_t index)
    {
        if (index < 0 || static_cast<std::uint64_t>(index) >= vertexCount_)
            ctx_.fail("face " + std::to_string(face_ + 1) + " of " + std::to_string(faces_.count) + " uses vertex " +
                      std::to_string(index) + ", but there are only " + std::to_string(vertexCount_) + " vertices");
        const auto v = static_cast<std::uint32_t>(index);
        if (corners_ == 0)
            first_ = v;
        else if (corners_ >= 2)
            out_.push_back({first_, previous_, v});
        previous_ = v;
        ++corners_;
    }

private:
    const PlyElement& faces_;
    std::uint64_t vertexCount_;
    const Context& ctx_;
    std::vector<Triangle>& out_;
    std::uint64_t face_ = 0;
    std::size_t corners_ = 0;
    std::uint32_t first_ = 0;
    std::uint32_t previous_ = 0;
};

} // namespace scandiff::io::detail::ply
