// SPDX-License-Identifier: GPL-3.0-or-later
#include "CliSupport.h"
#include "Commands.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/distance/CloudToMesh.h>


#include <chrono>
#include <iomanip>
#include <memory>
#include <optional>

namespace scandiff::cli {

void addCloudToMeshCommand(CLI::App& app, const PluginRegistry& registry, Streams streams)
{
    struct Args
    {
        std::string reference, compared, output;
        bool signedDistances = false;
        std::optional<double> maxDistance;
        bool clamp = false;
        int level = 0;
        int threads = 0;
        ReadFlags read;
        WriteFlags write;
    };
    auto args = std::make_shared<Args>();
    CLI::App* c = app.add_subcommand(
        "c2m", "Cloud-to-mesh distance: for each compared point, its exact distance to the reference mesh (thesis 000 §2.2)");
    c->add_option("--reference", args->reference, "Reference mesh (PLY, OBJ, STL, OFF...)")->required();
    c->add_option("--compared", args->compared, "Compared cloud (the output keeps its points, in order)")->required();
    c->add_option("-o,--output", args->output, "Output: the compared cloud with c2m_distance (nothing is written without it)");
    c->add_flag("--signed", args->signedDistances,
                "Signed distances: + on the side the closest triangle's normal points to (right-hand rule on its vertex order)");
    c->add_option("--max-dist", args->maxDistance, "Points farther than this (m) get NaN, or the maximum with --clamp")
        ->check(CLI::PositiveNumber);
    c->add_flag("--clamp", args->clamp, "With --max-dist: give farther points the maximum instead of NaN");
    c->add_option("--octree-level", args->level, "Grid level 1..21 (default: automatic, from the mean triangle size)")
        ->check(CLI::Range(0, 21));
    ThreadLimit::addOption(*c, args->threads);
    args->read.addTo(*c);
    args->write.addTo(*c);
    c->callback([args, &registry, streams] {
        // Parameters are checked before the (possibly long) reads.
        if (args->clamp && !args->maxDistance)
            throw Error(ErrorCode::InvalidArgument, "--clamp needs --max-dist");
        const ThreadLimit threadLimit(args->threads);
        CloudToMeshParams params;
        params.signedDistances = args->signedDistances;
        params.maxDistance = args->maxDistance;
        params.clampBeyondMax = args->clamp;
        params.octreeLevel = args->level;

        TerminalProgress progress;
        io::ReadOptions meshOptions;
        meshOptions.progress = &progress;
        const Mesh reference = io::readMesh(registry.formats, args->reference, meshOptions);
        PointCloud compared = io::readPointCloud(registry.formats, args->compared, args->read.toOptions(&progress));
        const auto start = std::chrono::steady_clock::now();
        CloudToMeshResult result = cloudToMesh(compared, reference, params, &progress);
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

        printStatistics(streams.out, std::string("c2m ") + (params.signedDistances ? "signed" : "unsigned") + " (compared -> mesh)",
                        result.statistics);
        streams.out << compared.size() << " points, " << reference.triangles.size() << " triangles ("
                    << result.degenerateTriangles << " degenerate), octree level " << result.level << ", " << std::fixed
                    << std::setprecision(3) << seconds << " s\n";
        if (!args->output.empty()) {
            compared.addField(std::move(result.distance));
            io::writePointCloud(registry.formats, compared, args->output, args->write.toOptions(&progress));
            streams.out << "wrote " << args->output << " (" << compared.size() << " points)\n";
        }
    });
}

} // namespace scandiff::cli
