// SPDX-License-Identifier: GPL-3.0-or-later
#include "CliSupport.h"
#include "Commands.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/distance/CloudToCloud.h>
#include <scandiff/core/distance/DistanceParameters.h>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <memory>
#include <optional>

namespace scandiff::cli {

void addCloudToCloudCommand(CLI::App& app, const PluginRegistry& registry, Streams streams)
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
    CLI::App* c = app.add_subcommand("c2c", "Cloud-to-cloud distance: for each compared point, its distance to the reference cloud (thesis 000 §2.3)");
    c->add_option("--reference", args->reference, "Reference cloud")->required();
    c->add_option("--compared", args->compared, "Compared cloud (the output keeps its points, in order)")->required();
    c->add_option("-o,--output", args->output,
                  "Output: the compared cloud with c2c_distance; with --closest-points also <name>_closest.<ext>, with --both-ways "
                  "<name>_reference.<ext> (nothing is written without it)");
    // The computation's options come from the declarations the workbench's dialog also uses.
    const auto options = addParameterOptions(*c, cloudToCloudParameters(), args->values);
    options.at("knn")->excludes(options.at("radius"));
    ThreadLimit::addOption(*c, args->threads);
    args->read.addTo(*c);
    args->write.addTo(*c);
    c->callback([args, &registry, streams] {
        const ThreadLimit threadLimit(args->threads);
        const ParameterValues values = resolveParameters(cloudToCloudParameters(), *args->values, "c2c");
        if (!args->output.empty())
            checkOutputFile(args->output, &registry.formats);

        TerminalProgress progress;
        const io::ReadOptions readOptions = args->read.toOptions(&progress);
        PointCloud reference = io::readPointCloud(registry.formats, args->reference, readOptions);
        PointCloud compared = io::readPointCloud(registry.formats, args->compared, readOptions);
        const auto start = std::chrono::steady_clock::now();
        CloudToCloudRun run = runCloudToCloud(compared, reference, values, &progress);
        const CloudToCloudParams& params = run.params;
        CloudToCloudResult& result = run.forward;
        std::optional<CloudToCloudResult>& reverse = run.reverse;
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        printStatistics(streams.out, "c2c " + std::string(localModelName(params.model)) + " (compared -> reference)",
                        result.statistics);
        if (reverse)
            printStatistics(streams.out, "c2c reverse (reference -> compared)", reverse->statistics);
        streams.out << "octree level " << result.level << ", " << std::fixed << std::setprecision(3) << seconds << " s\n";
        if (!args->output.empty()) {
            const std::filesystem::path out(args->output);
            const auto beside = [&](const std::string& suffix) {
                return out.parent_path() / (out.stem().string() + suffix + out.extension().string());
            };
            if (result.closest) {
                io::writePointCloud(registry.formats, *result.closest, beside("_closest"), args->write.toOptions(&progress));
                streams.out << "wrote " << beside("_closest").string() << '\n';
            }
            attachFields(compared, std::move(result));
            io::writePointCloud(registry.formats, compared, args->output, args->write.toOptions(&progress));
            streams.out << "wrote " << args->output << '\n';
            if (reverse) {
                attachFields(reference, std::move(*reverse));
                const auto referenceOutput = beside("_reference");
                io::writePointCloud(registry.formats, reference, referenceOutput, args->write.toOptions(&progress));
                streams.out << "wrote " << referenceOutput.string() << '\n';
            }
        }
    });
}

} // namespace scandiff::cli
