// SPDX-License-Identifier: GPL-3.0-or-later
//! The fuzzing corpus, read in every `make test`: each file of
//! tests/fuzz/corpus/<extension>/ (seeds, and inputs the fuzzers found
//! interesting) and each reproducer of tests/data/fuzz-found (files that once
//! crashed, hung or leaked a reader) must be read or refused with a
//! scandiff::Error naming the file; never a crash, never another exception.
//! Under `make sanitize` the same test runs with AddressSanitizer and
//! UndefinedBehaviorSanitizer.

#include "BuiltinFormats.h"
#include "TestSupport.h"

#include <scandiff/core/Error.h>
#include <scandiff/io/DxfReader.h>
#include <scandiff/io/FileIO.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

using namespace scandiff;
namespace fs = std::filesystem;

namespace {

//! Reads `file` as a file of extension `extension` (corpus files are named by
//! their hash): a copy with that extension in the test's folder.
void readOrRefuse(const io::FormatRegistry& registry, const fs::path& file, const std::string& extension, const fs::path& scratch)
{
    SCOPED_TRACE(file.string());
    const fs::path copy = scratch / ("input." + extension);
    fs::copy_file(file, copy, fs::copy_options::overwrite_existing);
    try {
        io::readFile(registry, copy);
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(copy.string()), std::string::npos) << "the message names the file: " << e.what();
        EXPECT_NE(e.code(), ErrorCode::Internal) << e.what();
    } catch (const std::exception& e) {
        ADD_FAILURE() << "not a scandiff::Error: " << e.what();
    }
    if (extension != "dxf")
        return;
    try {
        io::readDrawingDxf(copy); // the lines of the same file
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(copy.string()), std::string::npos) << "the message names the file: " << e.what();
        EXPECT_NE(e.code(), ErrorCode::Internal) << e.what();
    } catch (const std::exception& e) {
        ADD_FAILURE() << "not a scandiff::Error: " << e.what();
    }
}

} // namespace

TEST(FuzzCorpus, EveryFileIsReadOrRefusedCleanly)
{
    // tests/fuzz/corpus/MANIFEST lists every committed file: a file lost
    // from the corpus, or one added without being listed, fails here.
    const io::FormatRegistry registry = test::builtinFormats();
    const fs::path scratch = test::tempDir();
    const fs::path root = SCANDIFF_FUZZ_CORPUS_DIR;
    std::set<std::string> listed;
    {
        std::ifstream manifest(root / "MANIFEST");
        ASSERT_TRUE(manifest) << "no tests/fuzz/corpus/MANIFEST";
        for (std::string line; std::getline(manifest, line);)
            if (!line.empty())
                listed.insert(line);
    }
    std::set<std::string> found, extensions;
    for (const auto& folder : fs::directory_iterator(root)) {
        if (!folder.is_directory())
            continue;
        const std::string extension = folder.path().filename().string();
        extensions.insert(extension);
        for (const auto& entry : fs::directory_iterator(folder.path()))
            if (entry.is_regular_file()) {
                readOrRefuse(registry, entry.path(), extension, scratch);
                found.insert(extension + "/" + entry.path().filename().string());
            }
    }
    EXPECT_EQ(found, listed) << "the corpus and its MANIFEST differ";
    // Every format scandiff reads has its corpus.
    for (const io::FormatHandler& handler : registry.handlers()) {
        if (!handler.read)
            continue;
        bool covered = false;
        for (const std::string& extension : handler.extensions)
            covered = covered || extensions.count(extension);
        EXPECT_TRUE(covered) << "no corpus for " << handler.name;
    }
}

TEST(FuzzCorpus, EveryReproducerIsRefusedOrReadCleanly)
{
    const io::FormatRegistry registry = test::builtinFormats();
    const fs::path scratch = test::tempDir();
    std::size_t files = 0;
    for (const auto& entry : fs::directory_iterator(test::dataPath("fuzz-found")))
        if (entry.path().extension() != ".md") {
            readOrRefuse(registry, entry.path(), entry.path().extension().string().substr(1), scratch);
            ++files;
        }
    EXPECT_EQ(files, 18u);
}
