// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once
//! The OBJ, STL and OFF readers (MeshReaders.cpp), internal to io/.

#include <scandiff/core/Mesh.h>
#include <scandiff/io/FileIO.h>

#include <filesystem>

namespace scandiff::io::detail {

//! Reads an OBJ, STL (binary or ASCII) or OFF file, chosen by its extension.
//! Throws Error(InvalidData) naming the file and the problem (the line for
//! text files), Error(Io) when it cannot be opened, Error(Cancelled).
Mesh readMeshFile(const std::filesystem::path& path, const ReadOptions& options);

} // namespace scandiff::io::detail
