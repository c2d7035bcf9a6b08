// SPDX-License-Identifier: GPL-3.0-or-later
#include "CliSupport.h"
#include "Commands.h"

#include <memory>

namespace scandiff::cli {

void addConvertCommand(CLI::App& app, const PluginRegistry& registry, Streams streams)
{
    struct Args
    {
        std::string input, output;
        ReadFlags read;
        WriteFlags write;
    };
    auto args = std::make_shared<Args>();
    CLI::App* command = app.add_subcommand("convert", "Convert a cloud or mesh between formats (chosen by extension)");
    command->add_option("IN", args->input, "Input file")->required();
    command->add_option("OUT", args->output, "Output file")->required();
    args->read.addTo(*command);
    args->write.addTo(*command);
    command->callback([args, &registry, streams] {
        checkOutputFile(args->output, &registry.formats);
        TerminalProgress progress;
        const io::FormatHandler& source = registry.formats.forPath(args->input);
        const io::FormatHandler& target = registry.formats.forPath(args->output);
        const io::WriteOptions options = args->write.toOptions(&progress);
        // Scans stay scans between formats that hold several (E57 to E57);
        // into any other format they are merged, with a scan_index field.
        if (source.readAll && target.writeClouds) {
            const std::vector<io::Entity> parts = io::readEntities(registry.formats, args->input, args->read.toOptions(&progress));
            std::vector<const PointCloud*> clouds;
            std::size_t points = 0;
            for (const io::Entity& part : parts) {
                clouds.push_back(&pointsOf(part));
                points += clouds.back()->size();
            }
            io::writePointClouds(registry.formats, clouds, args->output, options);
            streams.out << "wrote " << args->output << " (" << points << " points in " << clouds.size() << " scans)\n";
            return;
        }
        const io::Entity entity = io::readFile(registry.formats, args->input, args->read.toOptions(&progress));
        // A mesh written to a points-only format keeps its vertices, as CloudCompare does.
        if (std::holds_alternative<Mesh>(entity) && !target.writeMesh)
            io::writePointCloud(registry.formats, std::get<Mesh>(entity).vertices, args->output, options);
        else
            io::writeFile(registry.formats, entity, args->output, options);
        const std::size_t points = std::holds_alternative<Mesh>(entity) ? std::get<Mesh>(entity).vertices.size()
                                                                         : std::get<PointCloud>(entity).size();
        streams.out << "wrote " << args->output << " (" << points << " points)\n";
    });
}

} // namespace scandiff::cli
