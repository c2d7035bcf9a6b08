// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/processing/MeshSampling.h>

#include <scandiff/core/Error.h>
#include <scandiff/core/SplitMix.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <unistd.h>

namespace scandiff {

PointCloud sampleMesh(const Mesh& mesh, const MeshSamplingParams& params, ProgressObserver* progress)
{
    if (!params.count && !(params.density > 0 && std::isfinite(params.density)))
        throw Error(ErrorCode::InvalidArgument, "mesh sampling: give a point count or a density > 0");
    mesh.checkConsistency();
    const PointCloud& v = mesh.vertices;
    const std::size_t triangles = mesh.triangles.size();
    std::vector<double> cumulative(triangles + 1, 0.0);
    for (std::size_t t = 0; t < triangles; ++t) {
        const auto& tri = mesh.triangles[t];
        const Eigen::Vector3d a = v.positions()[tri[0]].cast<double>(), b = v.positions()[tri[1]].cast<double>(),
                              c = v.positions()[tri[2]].cast<double>();
        const double area = 0.5 * (b - a).cross(c - a).norm();
        cumulative[t + 1] = cumulative[t] + (std::isfinite(area) ? area : 0.0);
    }
    const double total = cumulative.back();
    if (!(total > 0))
        throw Error(ErrorCode::InvalidData, "mesh sampling: mesh '" + mesh.name + "' has no area");
    const double wanted = params.count ? static_cast<double>(*params.count) : std::round(params.density * total);
    // Refused before anything is allocated: what the points would take against
    // the machine's memory (positions, normals, colours, every field).
    const double bytesPerPoint = 12.0 + (params.normals ? 12.0 : 0.0) + (v.hasColors() ? 3.0 : 0.0) + 4.0 * (v.fields().size() + 1);
    const double physical = static_cast<double>(::sysconf(_SC_PHYS_PAGES)) * static_cast<double>(::sysconf(_SC_PAGESIZE));
    if (wanted > 4e9 || (physical > 0 && wanted * bytesPerPoint > 0.8 * physical))
        throw Error(ErrorCode::InvalidArgument, "mesh sampling: " + std::to_string(static_cast<std::uint64_t>(wanted)) +
                                                    " points would need " + std::to_string(static_cast<int>(wanted * bytesPerPoint / 1e9)) +
                                                    " GB, more than this machine's memory allows");
    // Triangle t gets round(wanted * C(t+1) / total) - round(wanted * C(t) / total) points.
    std::vector<std::size_t> first(triangles + 1, 0);
    for (std::size_t t = 0; t <= triangles; ++t)
        first[t] = static_cast<std::size_t>(std::llround(wanted * (cumulative[t] / total)));
    first.back() = static_cast<std::size_t>(wanted);
    const std::size_t n = first.back();

    PointCloud out;
    out.name = (mesh.name.empty() ? mesh.vertices.name : mesh.name) + "_sampled";
    out.setOrigin(v.origin());
    out.resize(n);
    for (const auto& f : v.fields())
        out.addField(f.name()).setOffset(f.offset());
    // A float holds every integer up to 2^24: beyond, the index would be
    // rounded, so very large meshes get no index field.
    const bool indexField = triangles <= (std::size_t(1) << 24);
    ScalarField* triangleIndex = indexField ? &out.addField(fields::kTriangleIndex) : nullptr;
    Eigen::Vector3f* normals = params.normals ? out.enableNormals().data() : nullptr;
    Rgb8* colours = v.hasColors() ? out.enableColors().data() : nullptr;
    std::vector<ScalarField*> targets;
    for (const auto& f : v.fields())
        targets.push_back(out.field(f.name()));
    ProgressTicker ticker(progress, "Sampling the mesh", triangles);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, triangles, 4096), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t t = range.begin(); t != range.end(); ++t) {
            if (first[t] == first[t + 1])
                continue;
            const auto& tri = mesh.triangles[t];
            const Eigen::Vector3d a = v.positions()[tri[0]].cast<double>(), b = v.positions()[tri[1]].cast<double>(),
                                  c = v.positions()[tri[2]].cast<double>();
            const Eigen::Vector3f normal = (b - a).cross(c - a).normalized().cast<float>();
            SplitMix64 rng(params.seed, t);
            for (std::size_t i = first[t]; i < first[t + 1]; ++i) {
                // Uniform in the triangle: the square-root warp of two uniforms.
                const double r1 = std::sqrt(rng.uniform()), r2 = rng.uniform();
                const double wa = 1 - r1, wb = r1 * (1 - r2), wc = r1 * r2;
                out.positions()[i] = (wa * a + wb * b + wc * c).cast<float>();
                if (normals)
                    normals[i] = normal;
                if (v.hasColors()) {
                    const Rgb8 &ca = v.colors()[tri[0]], &cb = v.colors()[tri[1]], &cc = v.colors()[tri[2]];
                    const auto blend = [&](std::uint8_t x, std::uint8_t y, std::uint8_t z) {
                        return static_cast<std::uint8_t>(std::clamp(std::lround(wa * x + wb * y + wc * z), 0L, 255L));
                    };
                    colours[i] = Rgb8{blend(ca.r, cb.r, cc.r), blend(ca.g, cb.g, cc.g), blend(ca.b, cb.b, cc.b)};
                }
                for (std::size_t f = 0; f < v.fields().size(); ++f) {
                    const auto& values = v.fields()[f].values();
                    targets[f]->values()[i] =
                        static_cast<float>(wa * values[tri[0]] + wb * values[tri[1]] + wc * values[tri[2]]);
                }
                if (triangleIndex)
                    triangleIndex->values()[i] = static_cast<float>(t);
            }
        }
        ticker.step(range.size());
    });
    return out;
}

} // namespace scandiff
