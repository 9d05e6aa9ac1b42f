// Triangle meshes and heightfields: height look-ups against analytic surfaces and against each other, and the
// OBJ reader on good, malformed and garbage input.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>

#include "rubble/error.h"
#include "shapes/shape.h"

namespace rubble::detail {
namespace {

const std::string kObjDir = std::string(RUBBLE_TEST_DATA_DIR) + "/obj/";

float wave(float x, float z) { return 2 * std::sin(x / 8) * std::cos(z / 8); }

// Grid mesh of (n+1)^2 samples spaced h apart from `origin`, each cell split along its (x0,z0)-(x1,z1) diagonal.
TriangleMeshDef gridMesh(int n, float h, float ox, float oz, float (*height)(float, float)) {
    TriangleMeshDef def;
    for (int r = 0; r <= n; ++r)
        for (int c = 0; c <= n; ++c) {
            const float x = ox + float(c) * h, z = oz + float(r) * h;
            def.vertices.push_back({x, height(x, z), z});
        }
    for (int r = 0; r < n; ++r)
        for (int c = 0; c < n; ++c) {
            const std::uint32_t a = r * (n + 1) + c, b = a + 1, d = a + (n + 1), e = d + 1;
            def.indices.insert(def.indices.end(), {a, d, e, a, e, b});
        }
    return def;
}

TEST(TriangleMesh, HeightMatchesAnalyticSurfaceWithinInterpolationError) {
    // y = 2 sin(x/8) cos(z/8): the Hessian's spectral norm is at most 1/32. Linear interpolation on a triangle of
    // circumradius R errs by at most |H| R^2 / 2; for right triangles of leg h = 1, R^2 = 1/2, so the bound is
    // 1/128. Plus 1e-5 for float rounding.
    const Shape shape = buildShape(gridMesh(64, 1, -32, -32, wave));
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> u(-32, 32);
    double worst = 0;
    for (int i = 0; i < 20000; ++i) {
        const float x = u(rng), z = u(rng);
        const std::optional<float> y = surfaceHeightAt(shape, x, z);
        ASSERT_TRUE(y) << x << ", " << z;
        worst = std::max(worst, double(std::abs(*y - wave(x, z))));
    }
    EXPECT_LE(worst, 1.0 / 128 + 1e-5);
    EXPECT_GT(worst, 1e-3);  // the bound is not vacuous: interpolation error is really there
    // Exactly at samples (and on the outer edge) the mesh reproduces the samples.
    for (float x : {-32.0f, -5.0f, 0.0f, 32.0f})
        for (float z : {-32.0f, 7.0f, 32.0f}) {
            ASSERT_TRUE(surfaceHeightAt(shape, x, z));
            EXPECT_NEAR(*surfaceHeightAt(shape, x, z), wave(x, z), 1e-5);
        }
    EXPECT_FALSE(surfaceHeightAt(shape, 32.5f, 0));
    EXPECT_FALSE(surfaceHeightAt(shape, 0, -40));
    EXPECT_FALSE(surfaceHeightAt(shape, NAN, 0));
    // The grid stays within its cap of 4 cells per triangle.
    EXPECT_LE(std::size_t(shape.mesh->cellsX) * shape.mesh->cellsZ, 4 * shape.mesh->triangleCount());
}

TEST(TriangleMesh, HighestSurfaceWinsAndDegenerateTrianglesAreSkipped) {
    TriangleMeshDef def;
    def.vertices = {{0, 0, 0}, {0, 0, 4},  {4, 0, 4}, {4, 0, 0},   // floor y = 0
                    {1, 3, 1}, {1, 3, 3},  {3, 3, 3}, {3, 3, 1},   // shelf y = 3 over the middle
                    {2, 0, 2}, {2, 10, 2}, {2, 5, 2}, {0, 9, 0}};  // a vertical sliver and a point-triangle
    def.indices = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7, 8, 9, 10, 11, 11, 11, 0, 9, 8};
    const Shape shape = buildShape(def);
    EXPECT_EQ(shape.mesh->triangleCount(), 7u);              // zero-area triangles are kept
    EXPECT_NEAR(*surfaceHeightAt(shape, 2, 2), 3, 1e-6);     // shelf above floor; the sliver has no height
    EXPECT_NEAR(*surfaceHeightAt(shape, 0.5f, 2), 0, 1e-6);  // only the floor
    EXPECT_FALSE(surfaceHeightAt(shape, 5, 2));
}

TEST(TriangleMesh, SkewedLargeTrianglesStillFound) {
    // One huge triangle among many small ones: it overlaps most cells and must be found from every one.
    TriangleMeshDef def = gridMesh(20, 0.1f, 0, 0, [](float, float) { return 0.0f; });
    const std::uint32_t base = std::uint32_t(def.vertices.size());
    def.vertices.insert(def.vertices.end(), {{-100, 5, -100}, {-100, 5, 104}, {104, 5, -100}});
    def.indices.insert(def.indices.end(), {base, base + 1, base + 2});
    const Shape shape = buildShape(def);
    EXPECT_NEAR(*surfaceHeightAt(shape, 1, 1), 5, 1e-6);
    EXPECT_NEAR(*surfaceHeightAt(shape, -90, 50), 5, 1e-6);
    EXPECT_FALSE(surfaceHeightAt(shape, 90, 90));  // beyond the hypotenuse x + z = 4
    EXPECT_NEAR(*surfaceHeightAt(shape, -1, 4.9f), 5, 1e-6);
    EXPECT_LE(std::size_t(shape.mesh->cellsX) * shape.mesh->cellsZ, 4 * shape.mesh->triangleCount());
}

TEST(Heightfield, AgreesWithMeshOfTheSameSamples) {
    HeightfieldDef field;
    field.rows = 17;
    field.columns = 23;
    field.spacing = {1.5f, 2, 0.75f};
    std::mt19937 rng(9);
    std::uniform_real_distribution<float> u(-1, 1);
    for (std::uint32_t i = 0; i < field.rows * field.columns; ++i) field.heights.push_back(u(rng));
    TriangleMeshDef mesh;
    for (std::uint32_t r = 0; r < field.rows; ++r)
        for (std::uint32_t c = 0; c < field.columns; ++c)
            mesh.vertices.push_back({float(c) * field.spacing.x, field.heights[r * field.columns + c] * field.spacing.y,
                                     float(r) * field.spacing.z});
    for (std::uint32_t r = 0; r + 1 < field.rows; ++r)
        for (std::uint32_t c = 0; c + 1 < field.columns; ++c) {
            const std::uint32_t a = r * field.columns + c, b = a + 1, d = a + field.columns, e = d + 1;
            mesh.indices.insert(mesh.indices.end(), {a, d, e, a, e, b});
        }
    const Shape hf = buildShape(field), ms = buildShape(mesh);
    const float maxX = 22 * 1.5f, maxZ = 16 * 0.75f;
    std::uniform_real_distribution<float> ux(-1, maxX + 1), uz(-1, maxZ + 1);
    int inside = 0;
    for (int i = 0; i < 20000; ++i) {
        const float x = ux(rng), z = uz(rng);
        const auto a = surfaceHeightAt(hf, x, z), b = surfaceHeightAt(ms, x, z);
        ASSERT_EQ(a.has_value(), b.has_value()) << x << ", " << z;
        if (!a) continue;
        ++inside;
        EXPECT_NEAR(*a, *b, 1e-5);  // same triangles, same test: only rounding of the look-up differs
    }
    EXPECT_GT(inside, 15000);
    // On a sample and on the diagonal, values are the samples and their average.
    EXPECT_NEAR(*surfaceHeightAt(hf, 3 * 1.5f, 2 * 0.75f), 2 * field.heights[2 * 23 + 3], 1e-6);
    const float mid = (field.heights[0] + field.heights[23 + 1]) * field.spacing.y / 2;
    EXPECT_NEAR(*surfaceHeightAt(hf, 0.75f, 0.375f), mid, 1e-5);
}

TEST(Heightfield, PlaneIsReproducedExactly) {
    // A linear height function is interpolated without error by any triangulation.
    HeightfieldDef field{4, 5, {}, {2, 1, 3}};
    for (std::uint32_t r = 0; r < 4; ++r)
        for (std::uint32_t c = 0; c < 5; ++c) field.heights.push_back(0.5f * float(c) * 2 - 0.25f * float(r) * 3 + 1);
    const Shape shape = buildShape(field);
    for (float x : {0.0f, 0.3f, 3.9f, 8.0f})
        for (float z : {0.0f, 4.4f, 9.0f}) EXPECT_NEAR(*surfaceHeightAt(shape, x, z), 0.5f * x - 0.25f * z + 1, 1e-5);
    EXPECT_FALSE(surfaceHeightAt(shape, -0.1f, 1));
    EXPECT_FALSE(surfaceHeightAt(shape, 1, 9.1f));
    EXPECT_FALSE(surfaceHeightAt(buildShape(SphereDef{1}), 0, 0));
}

std::string loadError(const std::string& path) {
    try {
        loadObj(path);
    } catch (const Error& e) {
        return e.what();
    }
    return "no error";
}

TEST(Obj, ReadsPolygonsWithTexturesNormalsAndComments) {
    const TriangleMeshDef quad = loadObj(kObjDir + "quad.obj");
    ASSERT_EQ(quad.vertices.size(), 4u);
    EXPECT_EQ(quad.indices, (std::vector<std::uint32_t>{0, 3, 2, 0, 2, 1}));  // fan from the first vertex
    const Shape shape = buildShape(quad);
    EXPECT_NEAR(*surfaceHeightAt(shape, 0.5f, 0.5f), 0, 1e-6);
}

TEST(Obj, AcceptsEveryFaceFormAndRelativeIndices) {
    const TriangleMeshDef m = loadObj(kObjDir + "forms.obj");
    ASSERT_EQ(m.vertices.size(), 4u);
    EXPECT_EQ(m.vertices[1], (Vec3{1, 0, -1}));     // '+1.0'
    EXPECT_EQ(m.vertices[2], (Vec3{1, 0.25f, 1}));  // exponent form, trailing comment
    EXPECT_EQ(m.indices, (std::vector<std::uint32_t>{0, 3, 2, 0, 2, 1, 0, 1, 2, 0, 3, 2}));
    const TriangleMeshDef crlf = loadObj(kObjDir + "crlf.obj");
    EXPECT_EQ(crlf.indices, (std::vector<std::uint32_t>{0, 2, 3, 0, 3, 1}));
}

TEST(Obj, TextInMemoryReadsAsItsFileDoes) {
    const TriangleMeshDef fromFile = loadObj(kObjDir + "forms.obj");
    const TriangleMeshDef fromText = parseObj(
        "v -1 0 -1\nv +1.0 0 -1\nv 1 0.25e0 1 # c\nv -1 0 1\nf 1 4 3\nf 1 3 2\nf 1 2 3\nf -4 -1 -2\n", "inline.obj");
    EXPECT_EQ(fromText.vertices, fromFile.vertices);
    EXPECT_EQ(fromText.indices, fromFile.indices);
    try {
        parseObj("v 0 0 0\nf 1 2 3\n", "archive/mesh.obj");
        ADD_FAILURE() << "a face past the vertices was accepted";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "archive/mesh.obj:2: face index 2 is out of range (1 vertices)");
    }
}

TEST(Obj, MalformedFilesNameFileAndLine) {
    const std::string d = kObjDir;
    EXPECT_EQ(loadError(d + "terrain.obj"), d + "terrain.obj:35: face index 40 is out of range (32 vertices)");
    EXPECT_EQ(loadError(d + "bad_number.obj"), d + "bad_number.obj:4: bad number 'zero' in a 'v' line");
    EXPECT_EQ(loadError(d + "short_face.obj"), d + "short_face.obj:4: face needs at least 3 vertices (got 2)");
    EXPECT_EQ(loadError(d + "zero_index.obj"),
              d + "zero_index.obj:4: face index 0 is invalid (OBJ indices start at 1)");
    EXPECT_EQ(loadError(d + "bad_relative.obj"), d + "bad_relative.obj:4: face index -4 is out of range (3 vertices)");
    EXPECT_EQ(loadError(d + "short_vertex.obj"), d + "short_vertex.obj:2: 'v' needs 3 coordinates (got 2)");
    EXPECT_EQ(loadError(d + "no_faces.obj"),
              d + "no_faces.obj: no faces (a triangle mesh needs at least one 'f' line)");
    EXPECT_EQ(loadError(d + "bad_face_token.obj"), d + "bad_face_token.obj:4: bad face vertex '1/2/3/4'");
    EXPECT_EQ(loadError(d + "nan_vertex.obj"), d + "nan_vertex.obj:1: vertex coordinate 'nan' is not finite");
    EXPECT_EQ(loadError(d + "missing.obj"), "cannot open " + d + "missing.obj: No such file or directory");
    EXPECT_EQ(loadError(d), d + ": is a directory, not an OBJ file");
}

TEST(Obj, BinaryGarbageNeverCrashes) {
    // Random bytes, and random bytes behind plausible statement keywords, must load or throw rubble::Error.
    const std::string path = ::testing::TempDir() + "rubble_garbage.obj";
    std::mt19937 rng(1234);
    const char* prefixes[] = {"", "v ", "f ", "v 1 2 3\nv 1 2 3\nv 1 2 3\nf ", "f 1/", "v 1e999 "};
    int loaded = 0;
    for (int trial = 0; trial < 300; ++trial) {
        std::string bytes = prefixes[trial % 6];
        const int n = int(rng() % 200);
        for (int i = 0; i < n; ++i) {
            const unsigned r = rng();
            // Mix raw bytes with digits, separators and newlines so parsers get past the first token.
            bytes += (r & 3) == 0 ? char(r >> 8) : "0123456789-+/ .e\nvf"[(r >> 8) % 19];
        }
        {
            std::ofstream out(path, std::ios::binary);
            out << bytes;
        }
        try {
            const TriangleMeshDef m = loadObj(path);
            for (std::uint32_t i : m.indices) ASSERT_LT(i, m.vertices.size());
            ++loaded;
        } catch (const Error&) {
        }
    }
    std::remove(path.c_str());
    SUCCEED() << loaded << " garbage files happened to be valid OBJ";
}

}  // namespace
}  // namespace rubble::detail
