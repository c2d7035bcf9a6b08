// SPDX-License-Identifier: GPL-3.0-or-later
#include "CliSupport.h"
#include "Commands.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/distance/CloudToMesh.h>
#include <scandiff/core/distance/DistanceParameters.h>
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
        std::shared_ptr<std::map<std::string, std::string>> values = std::make_shared<std::map<std::string, std::string>>();
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
    // The computation's options come from the declarations the workbench's dialog also uses.
    addParameterOptions(*c, cloudToMeshParameters(), args->values);
    ThreadLimit::addOption(*c, args->threads);
    args->read.addTo(*c);
    args->write.addTo(*c);
    c->callback([args, &registry, streams] {
        // Parameters are checked before the (possibly long) reads.
        const CloudToMeshParams params = cloudToMeshSettings(resolveParameters(cloudToMeshParameters(), *args->values, "c2m"));
        const ThreadLimit threadLimit(args->threads);
        if (!args->output.empty())
            checkOutputFile(args->output, &registry.formats);

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
