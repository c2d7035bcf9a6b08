// SPDX-License-Identifier: GPL-3.0-or-later
// The processing tools from the command line: one subcommand each, inputs by
// role, outputs written beside -o, tables and matrices printed or saved.
#include "CliRunner.h"

#include <scandiff/core/Error.h>

#include "DxfCheck.h"
#include "TestSupport.h"

#include <Eigen/Geometry>

#include <iomanip>
#include <random>
#include <sstream>

using namespace scandiff;

namespace {

//! A georeferenced wavy terrain with a field, written as PLY.
std::filesystem::path terrain(const PluginRegistry& registry, const std::filesystem::path& path, std::uint32_t seed, double shift)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 10.0f);
    PointCloud cloud;
    cloud.name = path.stem().string();
    cloud.setOrigin({512000 + shift, 5423000, 100});
    cloud.resize(3000);
    ScalarField& f = cloud.addField("intensity");
    for (std::size_t i = 0; i < cloud.size(); ++i) {
        const float x = u(rng), y = u(rng);
        cloud.positions()[i] = {x, y, 0.2f * std::sin(x) * std::cos(y)};
        f.setValue(i, static_cast<double>(i % 100));
    }
    io::writePointCloud(registry.formats, cloud, path);
    return path;
}

} // namespace

TEST(ProcessingCli, NormalsSubsampleAndFieldsWriteTheirOutputs)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const auto input = terrain(registry, dir / "t.ply", 1, 0).string();

    test::CliRun r = test::runCliInProcess(registry, {"normals", input, "--radius", "0.5", "--orient", "+z", "-o", (dir / "n.ply").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    const PointCloud withNormals = io::readPointCloud(registry.formats, dir / "n.ply");
    ASSERT_TRUE(withNormals.hasNormals());
    ASSERT_NE(withNormals.field("surface_variation"), nullptr);
    ASSERT_NE(withNormals.field("intensity"), nullptr); // every field kept
    for (const auto& n : withNormals.normals())
        ASSERT_GT(n.z(), 0.9f);

    r = test::runCliInProcess(registry, {"subsample", input, "--spatial", "0.3", "-o", (dir / "s.ply").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("kept"), std::string::npos);
    const PointCloud sparse = io::readPointCloud(registry.formats, dir / "s.ply");
    EXPECT_LT(sparse.size(), 3000u);
    EXPECT_NE(sparse.field("intensity"), nullptr);

    r = test::runCliInProcess(registry, {"field", input, "--expr", "high = intensity >= 50", "-o", (dir / "f.ply").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(io::readPointCloud(registry.formats, dir / "f.ply").field("high")->value(75), 1.0);

    // A table: printed as CSV without -o, written with it.
    r = test::runCliInProcess(registry, {"field-histogram", input, "--field", "intensity", "--bins", "4"});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("bin_min,bin_max,count\n0,24.75,750\n"), std::string::npos) << r.out;
    r = test::runCliInProcess(registry, {"field-histogram", input, "--field", "intensity", "--bins", "4", "-o", (dir / "h.csv").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(test::readBytes(dir / "h.csv").substr(0, 22), "bin_min,bin_max,count\n");

    // Alternatives, required parameters and unknown fields are clear errors.
    r = test::runCliInProcess(registry, {"subsample", input, "--spatial", "0.3", "--random", "5"});
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("only one of"), std::string::npos) << r.err;
    r = test::runCliInProcess(registry, {"features", input});
    EXPECT_NE(r.status, 0);
    r = test::runCliInProcess(registry, {"field-smooth", input, "--field", "missing", "--sigma", "1"});
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.err.find("intensity"), std::string::npos) << r.err; // names the fields it has
}

TEST(ProcessingCli, MergeTransformAndCropKeepGlobalCoordinates)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const auto a = terrain(registry, dir / "a.ply", 1, 0).string();
    const auto b = terrain(registry, dir / "b.ply", 2, 3000).string(); // another shift, 3 km east
    test::CliRun r = test::runCliInProcess(registry, {"merge", a, b, "-o", (dir / "m.ply").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    const PointCloud merged = io::readPointCloud(registry.formats, dir / "m.ply");
    const PointCloud cloudB = io::readPointCloud(registry.formats, b);
    ASSERT_EQ(merged.size(), 6000u);
    EXPECT_LT((merged.globalPosition(3000 + 17) - cloudB.globalPosition(17)).norm(), 1e-3);
    EXPECT_EQ(merged.field("source_index")->value(5999), 1.0);

    // The transformation: the cloud moved, the matrix written beside it.
    r = test::runCliInProcess(registry, {"transform", a, "--rotate", "z,90", "--centre", "512005,5423005,100", "-o", (dir / "r.ply").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(std::filesystem::exists(dir / "r_matrix.txt"));
    EXPECT_NE(r.out.find("Applied matrix"), std::string::npos);
    // Inverting the written matrix file brings the points back.
    r = test::runCliInProcess(registry, {"transform", (dir / "r.ply").string(), "--matrix", (dir / "r_matrix.txt").string(), "--inverse", "-o",
                       (dir / "back.ply").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    const PointCloud original = io::readPointCloud(registry.formats, a), back = io::readPointCloud(registry.formats, dir / "back.ply");
    for (std::size_t i = 0; i < original.size(); i += 37)
        ASSERT_LT((back.globalPosition(i) - original.globalPosition(i)).norm(), 1e-4) << i;

    // Crop by a polygon given as repeated values.
    r = test::runCliInProcess(registry, {"crop", a, "--polygon", "512000,5423000", "512005,5423000", "512005,5423005", "512000,5423005", "-o",
                       (dir / "c.ply").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    const PointCloud cropped = io::readPointCloud(registry.formats, dir / "c.ply");
    EXPECT_GT(cropped.size(), 500u);
    for (std::size_t i = 0; i < cropped.size(); ++i) {
        const Eigen::Vector3d p = cropped.globalPosition(i);
        ASSERT_TRUE(p.x() >= 512000 && p.x() <= 512005 && p.y() >= 5423000 && p.y() <= 5423005) << i;
    }
}

TEST(ProcessingCli, MeshThenSampleThenCompare)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const auto input = terrain(registry, dir / "t.ply", 3, 0).string();
    test::CliRun r = test::runCliInProcess(registry, {"mesh", input, "--max-edge", "1", "-o", (dir / "mesh.ply").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    const Mesh mesh = io::readMesh(registry.formats, dir / "mesh.ply");
    EXPECT_GT(mesh.triangles.size(), 5000u);
    // Normals on a mesh's vertices keep its triangles.
    r = test::runCliInProcess(registry, {"normals", (dir / "mesh.ply").string(), "-o", (dir / "mesh_n.ply").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(io::readMesh(registry.formats, dir / "mesh_n.ply").triangles.size(), mesh.triangles.size());
    // Points sampled on the mesh lie on it: C2M gives zero, to the float rounding of their coordinates.
    r = test::runCliInProcess(registry, {"sample-mesh", (dir / "mesh.ply").string(), "--count", "2000", "-o", (dir / "samples.ply").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    r = test::runCliInProcess(registry, {"c2m", "--reference", (dir / "mesh.ply").string(), "--compared", (dir / "samples.ply").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    const auto at = r.out.find("max ");
    ASSERT_NE(at, std::string::npos) << r.out;
    EXPECT_LT(std::stod(r.out.substr(at + 4)), 1e-5) << r.out;
    // sample-mesh refuses a point cloud.
    r = test::runCliInProcess(registry, {"sample-mesh", input, "--count", "10"});
    EXPECT_EQ(r.status, 2);
}

TEST(ProcessingCli, SectionsWriteSlabsATableAndADxfDrawing)
{
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const auto input = terrain(registry, dir / "t.ply", 3, 0).string();
    const auto out = dir / "out";
    std::filesystem::create_directories(out);
    const test::CliRun r = test::runCliInProcess(
        registry, {"sections", input, "--axis", "x", "--thickness", "0.2", "--step", "2", "--out-dir", out.string()});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_NE(r.out.find("sections across x"), std::string::npos) << r.out;
    // The drawing: a layer per section, closed polylines, as DXF.
    ASSERT_TRUE(std::filesystem::exists(out / "sections.dxf"));
    const test::DxfCheck dxf = test::checkDxf(out / "sections.dxf"); // read and audited by ezdxf
    EXPECT_EQ(dxf.exitStatus, 0);
    EXPECT_GE(dxf.count("POLYLINE"), 5);
    for (const char* layer : {"POLYLINE@SECTION_0001", "POLYLINE@SECTION_0005"})
        EXPECT_GE(dxf.count(layer), 1) << layer;
    // One slab cloud per section, each exactly the points within 10 cm of its middle.
    ASSERT_TRUE(std::filesystem::exists(out / "table.csv"));
    const PointCloud all = io::readPointCloud(registry.formats, input);
    std::size_t slabs = 0;
    for (const auto& entry : std::filesystem::directory_iterator(out))
        if (entry.path().extension() == ".ply") {
            const PointCloud slab = io::readPointCloud(registry.formats, entry.path());
            ASSERT_GT(slab.size(), 0u);
            const double middle = slab.globalPosition(0).x();
            for (std::size_t i = 0; i < slab.size(); ++i)
                ASSERT_LT(std::abs(slab.globalPosition(i).x() - middle), 0.2 + 1e-6);
            ++slabs;
        }
    EXPECT_EQ(slabs, 5u); // middles at 0.1, 2.1, 4.1, 6.1, 8.1 m of a 10 m terrain
}

TEST(ProcessingCli, FilterByValueKeepsExactlyThePointsABruteForceKeeps)
{
    // Draws over the values fields hold: small integers (classes), signed
    // distances, GPS times whose microseconds only a double keeps; holes
    // without a value; bounds inside, on and around the values.
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    for (std::uint32_t seed = 1; seed <= 24; ++seed) {
        std::mt19937 rng(seed);
        PointCloud cloud;
        cloud.name = "draw";
        cloud.setOrigin({512000.0 * (seed % 3), 5423000.0 * (seed % 2), 0});
        const std::size_t n = 500 + seed * 37;
        cloud.resize(n);
        ScalarField& field = cloud.addField("value");
        const int kind = static_cast<int>(seed % 3);
        if (kind == 2)
            field.keepDoubles();
        std::uniform_real_distribution<double> unit(0.0, 1.0);
        for (std::size_t i = 0; i < n; ++i) {
            cloud.positions()[i] = Eigen::Vector3f(static_cast<float>(i), 0.0f, 0.0f);
            if (unit(rng) < 0.05)
                continue; // no value
            const double v = kind == 0 ? std::floor(unit(rng) * 10) : kind == 1 ? (unit(rng) - 0.5) * 0.2
                                                                                 : 1.4e9 + std::round(unit(rng) * 3.6e9) * 1e-6;
            field.setValue(i, v);
        }
        const std::string path = (dir / "draw.ply").string();
        io::writePointCloud(registry.formats, cloud, path);
        const PointCloud read = io::readPointCloud(registry.formats, path);
        const ScalarField& f = *read.field("value");
        // Bounds: two of the values themselves (bounds are included), or drawn.
        std::vector<std::size_t> withValue;
        for (std::size_t i = 0; i < n; ++i)
            if (f.hasValue(i))
                withValue.push_back(i);
        double a = f.value(withValue[rng() % withValue.size()]), b = f.value(withValue[rng() % withValue.size()]);
        if (seed % 4 == 0)
            a = f.range().min + (f.range().max - f.range().min) * unit(rng);
        if (a > b)
            std::swap(a, b);
        const bool outside = seed % 2 == 1;
        std::ostringstream low, high;
        low << std::setprecision(17) << a;
        high << std::setprecision(17) << b;
        std::vector<std::string> args = {"filter", path, "--field", "value", "--range", low.str(), high.str(), "-o", (dir / "kept.ply").string()};
        if (outside)
            args.push_back("--outside");
        const test::CliRun r = test::runCliInProcess(registry, args);
        ASSERT_EQ(r.status, 0) << r.err;
        std::vector<double> expected;
        for (std::size_t i : withValue) {
            const double v = f.value(i);
            if ((v >= a && v <= b) != outside)
                expected.push_back(v);
        }
        const PointCloud kept = io::readPointCloud(registry.formats, dir / "kept.ply");
        ASSERT_EQ(kept.size(), expected.size()) << "seed " << seed;
        const ScalarField& keptField = *kept.field("value");
        for (std::size_t k = 0; k < expected.size(); ++k)
            ASSERT_EQ(keptField.value(k), expected[k]) << "seed " << seed << " point " << k; // in order, every bit
    }
    // Bounds the wrong way round, one bound, a field the cloud lacks: clear errors, nothing written.
    const std::string input = terrain(registry, dir / "t.ply", 1, 0).string();
    const auto out = (dir / "none.ply").string();
    test::CliRun r = test::runCliInProcess(registry, {"filter", input, "--field", "intensity", "--range", "5", "1", "-o", out});
    EXPECT_EQ(r.status, 2) << r.err;
    EXPECT_NE(r.err.find("lower bound is above"), std::string::npos) << r.err;
    r = test::runCliInProcess(registry, {"filter", input, "--field", "nothing", "--range", "1", "5", "-o", out});
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("has no field 'nothing'"), std::string::npos) << r.err;
    r = test::runCliInProcess(registry, {"filter", input, "--field", "intensity", "--range", "1", "-o", out});
    EXPECT_NE(r.status, 0);
    EXPECT_FALSE(std::filesystem::exists(out));
    // The negative bounds of a signed distance are values, not options.
    r = test::runCliInProcess(registry, {"filter", input, "--field", "intensity", "--range", "-1", "9", "-o", out});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_EQ(io::readPointCloud(registry.formats, out).size(), 300u); // values 0..9 of i % 100, 30 points each
}

TEST(ProcessingCli, OutputPlacesAreCheckedOrCreatedBeforeTheInputsAreRead)
{
    // The input does not exist: a command that checks its outputs first
    // reports the output, not the input.
    const PluginRegistry registry = makePluginRegistry();
    const auto dir = test::tempDir();
    const std::string missingInput = (dir / "missing.ply").string();
    const std::string noFolder = (dir / "no" / "such" / "out.ply").string();
    const std::vector<std::vector<std::string>> commands = {
        {"normals", missingInput, "--radius", "0.5", "-o", noFolder},
        {"c2c", "--reference", missingInput, "--compared", missingInput, "-o", noFolder},
        {"c2m", "--reference", missingInput, "--compared", missingInput, "-o", noFolder},
        {"convert", missingInput, noFolder},
        {"field-histogram", missingInput, "--field", "f", "--report", noFolder + ".json"},
    };
    for (const auto& command : commands) {
        const test::CliRun r = test::runCliInProcess(registry, command);
        EXPECT_NE(r.status, 0) << command.front();
        EXPECT_NE(r.err.find("does not exist"), std::string::npos) << command.front() << ": " << r.err;
        EXPECT_EQ(r.err.find("missing.ply"), std::string::npos) << command.front() << ": " << r.err;
    }
    // A format scandiff does not write, refused as early.
    test::CliRun r = test::runCliInProcess(registry, {"subsample", missingInput, "--spatial", "1", "-o", (dir / "out.unknown").string()});
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("unknown"), std::string::npos) << r.err;
    EXPECT_EQ(r.err.find("missing.ply"), std::string::npos) << r.err;

    // --out-dir is created, parents and all, for the registry's tools and for segment.
    const std::string input = terrain(registry, dir / "t.ply", 2, 0).string();
    const auto created = dir / "new" / "folder";
    r = test::runCliInProcess(registry, {"sections", input, "--axis", "x", "--thickness", "0.2", "--step", "4", "--out-dir", created.string()});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(std::filesystem::exists(created / "sections.dxf"));
    r = test::runCliInProcess(registry, {"segment", input, "--field", "intensity", "--range", "90", "99", "--out-dir", (dir / "s" / "t").string()});
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(std::filesystem::exists(dir / "s" / "t" / "regions.csv"));
    // The four that used to refuse a missing folder only after computing:
    // the folder is made before the input is even read.
    for (const std::vector<std::string>& command : std::vector<std::vector<std::string>>{
             {"primitives", missingInput}, {"contours", missingInput}, {"stones", missingInput}, {"register-stations", missingInput, missingInput}}) {
        const auto folder = dir / ("made-by-" + command.front()) / "x";
        std::vector<std::string> args = command;
        args.insert(args.end(), {"--out-dir", folder.string()});
        r = test::runCliInProcess(registry, args);
        EXPECT_NE(r.status, 0) << command.front();
        EXPECT_NE(r.err.find("missing.ply"), std::string::npos) << command.front() << ": " << r.err;
        EXPECT_TRUE(std::filesystem::is_directory(folder)) << command.front();
    }
    // A file where the folder should be: refused, the file untouched.
    r = test::runCliInProcess(registry, {"sections", input, "--axis", "x", "--thickness", "0.2", "--step", "4", "--out-dir", input});
    EXPECT_NE(r.status, 0);
    EXPECT_NE(r.err.find("is a file"), std::string::npos) << r.err;
    EXPECT_EQ(io::readPointCloud(registry.formats, input).size(), 3000u);
}
