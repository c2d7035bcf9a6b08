// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! `scandiff-mpi c2c`: the cloud-to-cloud distance of scandiff-cli, split into
//! tiles over MPI ranks, value for value the same (docs/scale-out.md).

#include "Mpi.h"
#include "TiledRun.h"

#include <scandiff/core/ToolRegistry.h>
#include <scandiff/io/FileIO.h>

#include <filesystem>
#include <optional>
#include <ostream>

namespace scandiff::mpi {

struct CloudToCloudJob
{
    std::filesystem::path reference, compared, output; //!< no output: statistics only
    ParameterValues values;                            //!< resolved from cloudToCloudParameters()
    TilingOptions tiling;
    io::ReadOptions read;
    io::WriteOptions write;
};

//! The halo the options imply: the maximum distance when there is one, twice
//! the model radius with --radius, else a tenth of the tile (a point whose
//! neighbours lie farther is widened, not wrong).
double defaultHalo(const ParameterValues& values, double tileSize);

//! Collective. Rank 0 prints the statistics and the per-rank report on `out`
//! and writes the output. Throws Error like scandiff-cli for bad options or
//! files (on every rank alike, before any collective call).
void runTiledCloudToCloud(const Communicator& c, const io::FormatRegistry& formats, const CloudToCloudJob& job,
                          std::ostream& out);

} // namespace scandiff::mpi
