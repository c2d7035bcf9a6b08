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
        TerminalProgress progress;
        const io::Entity entity = io::readFile(registry.formats, args->input, args->read.toOptions(&progress));
        const io::FormatHandler& target = registry.formats.forPath(args->output);
        const io::WriteOptions options = args->write.toOptions(&progress);
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
