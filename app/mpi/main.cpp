// SPDX-License-Identifier: GPL-3.0-or-later
//! scandiff-mpi: scandiff-cli's comparisons split into tiles over MPI ranks
//! (`mpirun -np N scandiff-mpi c2c ...`, docs/scale-out.md). A separate
//! executable so that scandiff-cli and the workbench never need MPI.

#include "Mpi.h"
#include "TiledRun.h"
#include "TiledCloudToCloud.h"
#include "TiledCloudToMesh.h"
#include "TiledM3c2.h"

#include "CliSupport.h"

#include <scandiff/core/ClassSelection.h>
#include <scandiff/core/Error.h>
#include <scandiff/core/distance/DistanceParameters.h>
#include <scandiff/io/FileIO.h>

#include <CLI/CLI.hpp>

#include <cstdlib>
#include <malloc.h>
#include <iostream>
#include <memory>
#include <string>

namespace {

//! c2c's parameters but the classes: the tiles are cut and merged over every
//! point, and a run on some classes is not there yet (scandiff-cli c2c has it).
const std::vector<scandiff::ParameterSpec>& tiledCloudToCloudParameters()
{
    static const std::vector<scandiff::ParameterSpec> parameters = [] {
        std::vector<scandiff::ParameterSpec> kept;
        for (const auto& spec : scandiff::cloudToCloudParameters())
            if (spec.name != scandiff::kClassesParameter && spec.name != scandiff::kExcludeClassesParameter)
                kept.push_back(spec);
        return kept;
    }();
    return parameters;
}

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
                           "Reference margin each rank reads around its tiles, metres (default: what the options imply, see "
                           "docs/scale-out.md; c2c and c2m widen the points needing more, never wrong)");
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

//! What every subcommand takes beside its computation's options.
struct Args
{
    std::string reference, compared, corePoints, output;
    std::shared_ptr<std::map<std::string, std::string>> values = std::make_shared<std::map<std::string, std::string>>();
    int threads = 0;
    cli::ReadFlags read;
    cli::WriteFlags write;
    TilingFlags tiling;

    //! The job of a subcommand from its options, its values resolved
    //! against its computation's parameters.
    template <class Job>
    Job job(const std::vector<ParameterSpec>& parameters, const char* command) const
    {
        Job made;
        made.reference = reference;
        made.compared = compared;
        made.output = output;
        made.values = resolveParameters(parameters, *values, command);
        made.tiling = tiling.options();
        made.read = read.toOptions(nullptr);
        made.write = write.toOptions(nullptr);
        return made;
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

    const auto addCommon = [](CLI::App& command, Args& args, const char* what) {
        command.add_option("-o,--output", args.output, std::string("Output: ") + what + " (PLY; written by rank 0)");
        cli::ThreadLimit::addOption(command, args.threads);
        args.read.addTo(command);
        args.write.addTo(command);
        args.tiling.addTo(command);
    };

    Args c2cArgs;
    CLI::App* c2c = app.add_subcommand("c2c", "Cloud-to-cloud distance, as scandiff-cli c2c, on tiles over the ranks");
    c2c->add_option("--reference", c2cArgs.reference, "Reference cloud")->required();
    c2c->add_option("--compared", c2cArgs.compared, "Compared cloud (the output keeps its points, in order)")->required();
    const auto options = cli::addParameterOptions(*c2c, tiledCloudToCloudParameters(), c2cArgs.values);
    options.at("knn")->excludes(options.at("radius"));
    addCommon(*c2c, c2cArgs, "the compared cloud with c2c_distance");
    c2c->callback([&] {
        const cli::ThreadLimit threadLimit(c2cArgs.threads);
        auto job = c2cArgs.job<mpi::CloudToCloudJob>(tiledCloudToCloudParameters(), "c2c");
        mpi::runTiledCloudToCloud(world, formats, job, out);
    });

    Args c2mArgs;
    CLI::App* c2m = app.add_subcommand("c2m", "Cloud-to-mesh distance, as scandiff-cli c2m, on tiles of the compared cloud over the ranks");
    c2m->add_option("--reference", c2mArgs.reference, "Reference mesh (PLY, OBJ, STL, OFF...; every rank reads it, keeps its part)")
        ->required();
    c2m->add_option("--compared", c2mArgs.compared, "Compared cloud (the output keeps its points, in order)")->required();
    cli::addParameterOptions(*c2m, cloudToMeshParameters(), c2mArgs.values);
    addCommon(*c2m, c2mArgs, "the compared cloud with c2m_distance");
    c2m->callback([&] {
        const cli::ThreadLimit threadLimit(c2mArgs.threads);
        auto job = c2mArgs.job<mpi::CloudToMeshJob>(cloudToMeshParameters(), "c2m");
        mpi::runTiledCloudToMesh(world, formats, job, out);
    });

    Args m3c2Args;
    CLI::App* m3c2 = app.add_subcommand("m3c2", "M3C2, as scandiff-cli m3c2, on tiles of the core points over the ranks");
    m3c2->add_option("--reference", m3c2Args.reference, "The first epoch: its normals orient the comparison")->required();
    m3c2->add_option("--compared", m3c2Args.compared, "The second epoch")->required();
    m3c2->add_option("--core-points", m3c2Args.corePoints, "Where to measure (default: every reference point)");
    cli::addParameterOptions(*m3c2, m3c2Parameters(), m3c2Args.values);
    addCommon(*m3c2, m3c2Args, "the core points with their normals and the m3c2_* fields");
    m3c2->callback([&] {
        const cli::ThreadLimit threadLimit(m3c2Args.threads);
        auto job = m3c2Args.job<mpi::M3c2Job>(m3c2Parameters(), "m3c2");
        job.corePoints = m3c2Args.corePoints;
        mpi::runTiledM3c2(world, formats, job, out);
    });

    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return world.rank() == 0 ? app.exit(e, std::cout, std::cerr) : e.get_exit_code();
    } catch (const Error& e) {
        // Option and file errors arise on every rank alike (the one
        // collective call before the run, the origin's box, tells every rank
        // of a share one rank alone could not read): rank 0 says it, all
        // return its status.
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
    // Buffers from 4 MiB up are mapped on their own and go back to the system
    // when freed. glibc otherwise raises this threshold to the size of the
    // largest buffer freed so far (the chunks of coordinates a rank reads,
    // 25 MB each), and the buffers that follow come from a heap that keeps
    // its holes: a rank's peak was 15 % higher.
    mallopt(M_MMAP_THRESHOLD, 4 << 20);
    // A rank waiting in a collective call gives its core away instead of
    // polling: with more ranks than cores (a workstation, a shared node) the
    // ranks still computing get it. OpenMPI reads this before MPI_Init; a value
    // set by the user (mpirun --mca) wins.
    setenv("OMPI_MCA_mpi_yield_when_idle", "1", 0);
    // Every rank on this machine (OpenMPI gives each process both sizes
    // before MPI_Init): shared memory carries every message, through
    // OpenMPI's own ob1 layer, and probing the network fabrics' libraries
    // (libfabric, PSM) for the other layer costs 0.2 s of the start, out of
    // a 6 s run on 10 M points. Across machines nothing is changed; a value
    // set by the user wins.
    const char* localSize = std::getenv("OMPI_COMM_WORLD_LOCAL_SIZE");
    const char* worldSize = std::getenv("OMPI_COMM_WORLD_SIZE");
    if (localSize && worldSize && std::string(localSize) == worldSize)
        setenv("OMPI_MCA_pml", "ob1", 0);
    MPI_Init(&argc, &argv);
    scandiff::mpi::memoryNote("started");
    const scandiff::mpi::Communicator world;
    const int status = run(argc, argv, world);
    MPI_Finalize();
    return status;
}
