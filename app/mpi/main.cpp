// SPDX-License-Identifier: GPL-3.0-or-later
//! scandiff-mpi: scandiff-cli's comparisons split into tiles over MPI ranks
//! (`mpirun -np N scandiff-mpi c2c ...`, docs/scale-out.md). A separate
//! executable so that scandiff-cli and the workbench never need MPI.

#include "Mpi.h"
#include "TiledCloudToCloud.h"

#include "CliSupport.h"

#include <scandiff/core/Error.h>
#include <scandiff/core/distance/DistanceParameters.h>
#include <scandiff/io/FileIO.h>

#include <CLI/CLI.hpp>

#include <cstdlib>
#include <iostream>
#include <memory>

namespace {

using namespace scandiff;

//! Options of every tiled command, beside the computation's own.
struct TilingFlags
{
    double tileSize = 100.0;
    double halo = -1.0;
    std::uint64_t chunkPoints = 1u << 20;

    void addTo(CLI::App& command)
    {
        command.add_option("--tile-size", tileSize, "Side of the square tiles the compared cloud is split into, metres")
            ->capture_default_str();
        command.add_option("--halo", halo,
                           "Reference margin each rank reads around its tiles, metres (default: the maximum distance, "
                           "twice the model radius, else a tenth of the tile; points needing more are widened, never wrong)");
        command.add_option("--chunk-points", chunkPoints, "Points read from a file at a time")->capture_default_str();
    }
    mpi::TilingOptions options() const
    {
        mpi::TilingOptions o;
        o.tileSize = tileSize;
        if (halo >= 0)
            o.halo = halo;
        o.chunkPoints = chunkPoints;
        return o;
    }
};

int run(int argc, char** argv, const mpi::Communicator& world)
{
    io::FormatRegistry formats;
    io::registerBuiltinFormats(formats);
    // Only rank 0 speaks; the others compute as quietly (their errors still show).
    static std::ostream silent(nullptr);
    std::ostream& out = world.rank() == 0 ? std::cout : silent;

    CLI::App app{"scandiff-mpi: scandiff-cli's comparisons on tiles over MPI ranks (mpirun -np N scandiff-mpi ...)"};
    app.require_subcommand(1);
    app.set_version_flag("--version", "scandiff 0.1.0");

    struct Args
    {
        std::string reference, compared, output;
        std::shared_ptr<std::map<std::string, std::string>> values = std::make_shared<std::map<std::string, std::string>>();
        int threads = 0;
        cli::ReadFlags read;
        cli::WriteFlags write;
        TilingFlags tiling;
    } args;
    CLI::App* c2c = app.add_subcommand("c2c", "Cloud-to-cloud distance, as scandiff-cli c2c, on tiles over the ranks");
    c2c->add_option("--reference", args.reference, "Reference cloud")->required();
    c2c->add_option("--compared", args.compared, "Compared cloud (the output keeps its points, in order)")->required();
    c2c->add_option("-o,--output", args.output, "Output: the compared cloud with c2c_distance (PLY; written by rank 0)");
    const auto options = cli::addParameterOptions(*c2c, cloudToCloudParameters(), args.values);
    options.at("knn")->excludes(options.at("radius"));
    cli::ThreadLimit::addOption(*c2c, args.threads);
    args.read.addTo(*c2c);
    args.write.addTo(*c2c);
    args.tiling.addTo(*c2c);
    c2c->callback([&] {
        const cli::ThreadLimit threadLimit(args.threads);
        mpi::CloudToCloudJob job;
        job.reference = args.reference;
        job.compared = args.compared;
        job.output = args.output;
        job.values = resolveParameters(cloudToCloudParameters(), *args.values, "c2c");
        job.tiling = args.tiling.options();
        job.read = args.read.toOptions(nullptr);
        job.write = args.write.toOptions(nullptr);
        mpi::runTiledCloudToCloud(world, formats, job, out);
    });

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return world.rank() == 0 ? app.exit(e, std::cout, std::cerr) : e.get_exit_code();
    } catch (const Error& e) {
        // Option and file errors arise on every rank alike, before any
        // collective call: rank 0 says it, all return its status.
        if (world.rank() == 0)
            std::cerr << "error: " << e.what() << '\n';
        return e.exitStatus();
    } catch (const std::exception& e) {
        if (world.rank() == 0)
            std::cerr << "error: " << e.what() << '\n';
        return static_cast<int>(ErrorCode::Internal);
    }
    return 0;
}

} // namespace

int main(int argc, char** argv)
{
    // A rank waiting in a collective call gives its core away instead of
    // polling: with more ranks than cores (a workstation, a shared node) the
    // ranks still computing get it. OpenMPI reads this before MPI_Init; a value
    // set by the user (mpirun --mca) wins.
    setenv("OMPI_MCA_mpi_yield_when_idle", "1", 0);
    MPI_Init(&argc, &argv);
    const scandiff::mpi::Communicator world;
    const int status = run(argc, argv, world);
    MPI_Finalize();
    return status;
}
