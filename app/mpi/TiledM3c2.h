// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! `scandiff-mpi m3c2`: scandiff-cli's M3C2 on tiles of the core points over
//! MPI ranks, value for value the same (docs/scale-out.md).

#include "Mpi.h"
#include "TiledRun.h"

#include <scandiff/core/ToolRegistry.h>
#include <scandiff/io/FileIO.h>

#include <filesystem>
#include <ostream>

namespace scandiff::mpi {

struct M3c2Job
{
    std::filesystem::path reference, compared, corePoints, output; //!< no core points: every reference point
    ParameterValues values;                                         //!< resolved from m3c2Parameters()
    TilingOptions tiling;
    io::ReadOptions read;
    io::WriteOptions write;
};

//! Collective. Rank 0 prints the summary and the per-rank report on `out` and
//! writes the core points with their M3C2 fields. Throws Error like
//! scandiff-cli for bad options or files (on every rank alike, before any
//! collective call).
void runTiledM3c2(const Communicator& c, const io::FormatRegistry& formats, const M3c2Job& job, std::ostream& out);

} // namespace scandiff::mpi
