// SPDX-License-Identifier: GPL-3.0-or-later
#include <scandiff/core/Error.h>
#include <scandiff/io/FileIO.h>

#include "TestSupport.h"

using namespace scandiff;

namespace {

ErrorCode readError(const io::FormatRegistry& registry, const std::filesystem::path& path, std::string* message = nullptr)
{
    try {
        io::readFile(registry, path);
    } catch (const Error& e) {
        if (message)
            *message = e.what();
        return e.code();
    }
    return ErrorCode::Internal;
}

io::FormatRegistry builtins()
{
    io::FormatRegistry registry;
    io::registerBuiltinFormats(registry);
    return registry;
}

} // namespace

TEST(FileIO, ExtensionsAreCaseInsensitive)
{
    const auto registry = builtins();
    EXPECT_EQ(registry.forPath("scan.PLY").name, registry.forPath("scan.ply").name);
    EXPECT_EQ(io::lowerExtension("a/b/C.LaS"), "las");
}

TEST(FileIO, UnknownExtensionAndLazAreUnsupported)
{
    const auto registry = builtins();
    const auto dir = test::tempDir();
    test::writeText(dir / "scan.e57", "x");
    test::writeText(dir / "scan.laz", "LASF");
    std::string message;
    EXPECT_EQ(readError(registry, dir / "scan.e57", &message), ErrorCode::Unsupported);
    EXPECT_NE(message.find("scan.e57"), std::string::npos);
    EXPECT_EQ(readError(registry, dir / "scan.laz", &message), ErrorCode::Unsupported);
    EXPECT_NE(message.find("compressed LAS"), std::string::npos);
}

TEST(FileIO, MissingAndEmptyFilesNameTheFile)
{
    const auto registry = builtins();
    const auto dir = test::tempDir();
    std::string message;
    for (const char* name : {"missing.ply", "missing.las", "missing.xyz", "missing.obj"}) {
        EXPECT_EQ(readError(registry, dir / name, &message), ErrorCode::Io) << name;
        EXPECT_NE(message.find(name), std::string::npos) << message;
    }
    for (const char* name : {"empty.ply", "empty.las", "empty.xyz", "empty.obj", "empty.stl", "empty.off"}) {
        test::writeText(dir / name, "");
        const ErrorCode code = readError(registry, dir / name, &message);
        EXPECT_EQ(code, ErrorCode::InvalidData) << name << ": " << message;
        EXPECT_NE(message.find(name), std::string::npos) << message;
    }
}

TEST(FileIO, WritingAPointCloudToAMeshOnlyFormatIsRefused)
{
    const auto registry = builtins();
    PointCloud cloud;
    cloud.resize(2);
    EXPECT_THROW(io::writePointCloud(registry, cloud, test::tempDir() / "cloud.obj"), Error);
}

TEST(FileIO, EveryBuiltinFormatIsRegistered)
{
    const auto registry = builtins();
    for (const char* ext : {"ply", "xyz", "txt", "csv", "pts", "asc", "las", "obj", "stl", "off", "dxf"})
        EXPECT_NO_THROW(registry.forPath(std::string("a.") + ext)) << ext;
}
