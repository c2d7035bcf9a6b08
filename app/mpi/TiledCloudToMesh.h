// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! `scandiff-mpi c2m`: the cloud-to-mesh distance of scandiff-cli, split into
//! tiles of the compared cloud over MPI ranks, value for value the same
//! (docs/scale-out.md).

#include "Mpi.h"
#include "TiledRun.h"

#include <scandiff/core/ToolRegistry.h>
#include <scandiff/io/FileIO.h>

#include <filesystem>
#include <ostream>

namespace scandiff::mpi {

struct CloudToMeshJob
{
    std::filesystem::path reference, compared, output; //!< reference: a mesh; no output: statistics only
    ParameterValues values;                            //!< resolved from cloudToMeshParameters()
    TilingOptions tiling;
    io::ReadOptions read;
    io::WriteOptions write;
};

//! Collective. Rank 0 prints the statistics and the per-rank report on `out`
//! and writes the output. Throws Error like scandiff-cli for bad options or
//! files (on every rank alike, before any collective call).
void runTiledCloudToMesh(const Communicator& c, const io::FormatRegistry& formats, const CloudToMeshJob& job, std::ostream& out);

} // namespace scandiff::mpi
