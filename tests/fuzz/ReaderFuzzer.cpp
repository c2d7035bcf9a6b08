// SPDX-License-Identifier: GPL-3.0-or-later
//! libFuzzer harness of one reader: the input bytes are written to a file of
//! the reader's extension (SCANDIFF_FUZZ_EXTENSION, one executable per reader)
//! and read through the registry, as the CLI and the workbench read files
//! (and by ranges of records, as scandiff-mpi's ranks read them). A
//! scandiff::Error is the expected answer to a broken file; a crash, a leak, a
//! timeout or an allocation past -rss_limit_mb is a bug. Built with
//! -DSCANDIFF_FUZZ=ON (clang); see docs/reliability.md for how to run it.

#include <scandiff/core/Error.h>
#include <scandiff/io/DxfReader.h>
#include <scandiff/io/E57.h>
#include <scandiff/io/FileIO.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

#ifndef SCANDIFF_FUZZ_EXTENSION
#error "SCANDIFF_FUZZ_EXTENSION must name the reader's extension"
#endif

namespace {

const scandiff::io::FormatRegistry& formats()
{
    static const scandiff::io::FormatRegistry registry = [] {
        scandiff::io::FormatRegistry r;
        scandiff::io::registerBuiltinFormats(r);
        return r;
    }();
    return registry;
}

//! One file per process in memory-backed /dev/shm when it exists.
const std::filesystem::path& inputPath()
{
    static const std::filesystem::path path = [] {
        const std::filesystem::path shm = "/dev/shm";
        const std::filesystem::path dir = std::filesystem::exists(shm) ? shm : std::filesystem::temp_directory_path();
        return dir / ("scandiff-fuzz-" + std::to_string(::getpid()) + "." SCANDIFF_FUZZ_EXTENSION);
    }();
    return path;
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size)
{
    {
        std::ofstream out(inputPath(), std::ios::binary | std::ios::trunc);
        out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
    }
    try {
        scandiff::io::readFile(formats(), inputPath());
    } catch (const scandiff::Error&) {
        // A clean refusal: what a broken file must give.
    }
    // Formats read by ranges of records (what scandiff-mpi's ranks do): the
    // count, two halves, their boxes and coordinates, and a range past the end, each a
    // clean answer or a clean refusal.
    auto refusedOrRead = [](auto&& read) {
        try {
            read();
        } catch (const scandiff::Error&) {
        }
    };
    refusedOrRead([&] {
        namespace io = scandiff::io;
        if (!io::canReadRecordRanges(formats(), inputPath()))
            return;
        const std::uint64_t n = io::pointRecordCount(formats(), inputPath());
        for (const io::RecordRange range : {io::RecordRange{0, n / 2}, io::RecordRange{n / 2, n - n / 2}}) {
            refusedOrRead([&] { io::pointRecordBounds(formats(), inputPath(), range); });
            refusedOrRead([&] { io::pointRecordPositions(formats(), inputPath(), range); });
            refusedOrRead([&] { io::readPointRecords(formats(), inputPath(), range); });
        }
        refusedOrRead([&] { io::readPointRecords(formats(), inputPath(), io::RecordRange{n, 1}); });
    });
    if (std::string(SCANDIFF_FUZZ_EXTENSION) == "e57") {
        try {
            scandiff::io::inspectE57(inputPath()); // scans and images as the XML lists them
            scandiff::io::readEntities(formats(), inputPath());
        } catch (const scandiff::Error&) {
        }
    }
    if (std::string(SCANDIFF_FUZZ_EXTENSION) == "dxf") {
        try {
            scandiff::io::readDrawingDxf(inputPath()); // the same file as a drawing (lines)
        } catch (const scandiff::Error&) {
        }
    }
    return 0;
}
