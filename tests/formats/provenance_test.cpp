// Provenance (formats/svo.md, "Metadata"): every member survives ProvenanceJson and
// ParseProvenance; the text has its keys in alphabetical order and follows from the values alone;
// the option text older files recorded reads as the same typed values; anything malformed or of
// another type is absent, never an exception; a source name that is not UTF-8 is escaped.

#include "svokit/formats/provenance.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace svokit {
namespace {

const std::string kGenerator = "svokit " SVOKIT_VERSION;

void ExpectSame(const Provenance& got, const Provenance& want) {
  EXPECT_EQ(got.source, want.source);
  EXPECT_EQ(got.triangles, want.triangles);
  EXPECT_EQ(got.grid, want.grid);
  EXPECT_EQ(got.voxelize, want.voxelize);
  EXPECT_EQ(got.build, want.build);
  EXPECT_EQ(got.bake, want.bake);
}

Provenance RoundTrip(const Provenance& p) {
  const Provenance back = ParseProvenance(ProvenanceJson(p));
  EXPECT_EQ(back.generator, kGenerator);
  return back;
}

// Every member set, each to a value other than its default.
Provenance Full() {
  Provenance p;
  p.source = "torus.obj";
  p.triangles = 1200;
  p.grid = GridFit{512, 0, 2};
  p.voxelize = VoxelSettings{VoxelMode::kThin, true, false, true};
  p.build = BuildSettings{2, false, SvoCompression{true, 7}};
  p.bake = BakeSettings{5, 1.5, 3.25, 0.5, 2, 9};
  return p;
}

TEST(Provenance, EveryMemberRoundTrips) {
  ExpectSame(RoundTrip(Full()), Full());

  for (const GridFit& grid : {GridFit{512, 0, 0}, GridFit{1, 0, 7}, GridFit{0, 0.01, 0},
                              GridFit{0, 1.0 / 3, 4}, GridFit{4096, 0, 4294967295u}}) {
    Provenance p = Full();
    p.grid = grid;
    ExpectSame(RoundTrip(p), p);
  }
  for (const VoxelMode mode : {VoxelMode::kConservative, VoxelMode::kThin}) {
    for (const bool colors : {false, true}) {
      for (const bool normals : {false, true}) {
        for (const bool solid : {false, true}) {
          Provenance p = Full();
          p.voxelize = VoxelSettings{mode, colors, normals, solid};
          SCOPED_TRACE(ProvenanceJson(p));
          ExpectSame(RoundTrip(p), p);
        }
      }
    }
  }
  // Without zstd no level is recorded: it reads back as the default.
  for (const std::uint32_t bricks : {3u, 2u, 0u}) {
    for (const bool contours : {true, false}) {
      for (const SvoCompression compression :
           {SvoCompression{true, 1}, SvoCompression{true, 3}, SvoCompression{true, 22},
            SvoCompression{false, 3}}) {
        Provenance p = Full();
        p.build = BuildSettings{bricks, contours, compression};
        SCOPED_TRACE(ProvenanceJson(p));
        ExpectSame(RoundTrip(p), p);
      }
    }
  }
  for (const std::optional<std::uint64_t> jitter :
       {std::optional<std::uint64_t>(), std::optional<std::uint64_t>(0),
        std::optional<std::uint64_t>(18446744073709551615u)}) {
    Provenance p = Full();
    p.bake = BakeSettings{16, 0.25, 57.2, 1, 1, jitter};
    SCOPED_TRACE(ProvenanceJson(p));
    ExpectSame(RoundTrip(p), p);
  }
}

TEST(Provenance, WhatIsNotSetStaysAbsent) {
  Provenance p;
  p.source = "only.ply";
  EXPECT_EQ(ProvenanceJson(p), R"({"generator":")" + kGenerator + R"(","source":"only.ply"})");
  const Provenance back = RoundTrip(p);
  ExpectSame(back, p);
  EXPECT_FALSE(back.grid || back.voxelize || back.build || back.bake);

  // A .vfrag's: a grid and the voxelization, no octree yet.
  Provenance vfrag = Full();
  vfrag.build.reset();
  vfrag.bake.reset();
  ExpectSame(RoundTrip(vfrag), vfrag);
}

// formats/svo.md: keys in alphabetical order, so the bytes follow from the values.
TEST(Provenance, KeysAreInAlphabeticalOrderAndTheTextFollowsFromTheValues) {
  EXPECT_EQ(ProvenanceJson(Full()),
            R"({"bake":{"aperture":1.5,"cones":5,"distance":3.25,"falloff":0.5,"jitter_seed":9,)"
            R"("offset":2.0,"term":"ao"},)"
            R"("build":{"bricks":2,"compression":"zstd","contours":false,"zstd_level":7},)"
            R"("generator":")" +
                kGenerator +
                R"(","grid":{"pad":2,"resolution":512},"source":"torus.obj","triangles":1200,)"
                R"("voxelize":{"color":true,"fill":"solid","mode":"thin","normal":false}})");
  Provenance by_size = Full();
  by_size.grid = GridFit{0, 0.01, 0};
  by_size.build = BuildSettings{0, true, SvoCompression{false, 3}};
  by_size.bake.reset();
  EXPECT_EQ(ProvenanceJson(by_size),
            R"({"build":{"bricks":0,"compression":"none","contours":true},"generator":")" +
                kGenerator +
                R"(","grid":{"pad":0,"voxel_size":0.01},"source":"torus.obj","triangles":1200,)"
                R"("voxelize":{"color":true,"fill":"solid","mode":"thin","normal":false}})");

  // Two Provenances of equal values, made apart and in another order, give the same text.
  Provenance a = Full(), b;
  b.bake = a.bake;
  b.build = a.build;
  b.voxelize = a.voxelize;
  b.grid = a.grid;
  b.triangles = a.triangles;
  b.source = std::string("torus") + ".obj";
  b.generator = "anything: it is not written";
  EXPECT_EQ(ProvenanceJson(a), ProvenanceJson(b));
  EXPECT_EQ(ProvenanceJson(ParseProvenance(ProvenanceJson(a))), ProvenanceJson(a));
}

// Files written before the typed members recorded each stage's option text.
TEST(Provenance, OptionTextReadsAsTheTypedValues) {
  const Provenance legacy = ParseProvenance(
      R"({"source":"torus.obj","triangles":1200,)"
      R"("voxelize":"--resolution 512 --pad 2 --mode thin --attributes color --fill solid",)"
      R"("build":"--bricks 2 --no-contours --compression zstd:7",)"
      R"("bake":"--ao --cones 5 --aperture 1.5 --distance 3.25 --falloff 0.5 --offset 2 )"
      R"(--jitter 9"})");
  ExpectSame(legacy, Full());

  const Provenance by_size = ParseProvenance(
      R"({"voxelize":"--voxel-size 0.01 --mode conservative --attributes color,normal",)"
      R"("build":"--bricks 3 --contours --compression none",)"
      R"("bake":"--ao --cones 16 --distance 57.2"})");
  EXPECT_EQ(by_size.grid, (GridFit{0, 0.01, 0}));
  EXPECT_EQ(by_size.voxelize, (VoxelSettings{VoxelMode::kConservative, true, true, false}));
  EXPECT_EQ(by_size.build, (BuildSettings{3, true, SvoCompression{false, 3}}));
  EXPECT_EQ(by_size.bake, (BakeSettings{16, 1, 57.2, 1, 1, std::nullopt}));

  // A .vfrag's "options"; no attributes and no fill: geometry only, a surface.
  const Provenance vfrag =
      ParseProvenance(R"({"source":"m.obj","options":"--resolution 64 --mode thin"})");
  EXPECT_EQ(vfrag.source, "m.obj");
  EXPECT_EQ(vfrag.grid, (GridFit{64, 0, 0}));
  EXPECT_EQ(vfrag.voxelize, (VoxelSettings{VoxelMode::kThin, false, false, false}));
  EXPECT_FALSE(vfrag.build || vfrag.bake);

  // zstd without a level: the default level.
  EXPECT_EQ(ParseProvenance(R"({"build":"--bricks 0 --compression zstd"})").build,
            (BuildSettings{0, false, SvoCompression{true, 3}}));
  // Option text with neither resolution nor voxel size: no grid, the voxelization still read.
  const Provenance no_grid = ParseProvenance(R"({"voxelize":"--mode thin --fill solid"})");
  EXPECT_FALSE(no_grid.grid);
  EXPECT_EQ(no_grid.voxelize, (VoxelSettings{VoxelMode::kThin, false, false, true}));
}

TEST(Provenance, MembersOfAnotherTypeAreAbsent) {
  const Provenance p = ParseProvenance(
      R"({"source":5,"generator":null,"triangles":-3,"grid":{"resolution":"512","pad":2},)"
      R"("voxelize":[1,2],"build":3,"bake":true})");
  EXPECT_EQ(p.source, "");
  EXPECT_EQ(p.generator, "");
  EXPECT_EQ(p.triangles, 0u);
  EXPECT_FALSE(p.grid);
  EXPECT_FALSE(p.voxelize);
  EXPECT_FALSE(p.build);
  EXPECT_FALSE(p.bake);

  EXPECT_EQ(ParseProvenance(R"({"triangles":1.5})").triangles, 0u);
  EXPECT_EQ(ParseProvenance(R"({"triangles":"7"})").triangles, 0u);
  // Inside an object: each member of another type takes the value an absent one gives.
  EXPECT_EQ(ParseProvenance(R"({"grid":{"resolution":64,"pad":"2"}})").grid, (GridFit{64, 0, 0}));
  EXPECT_FALSE(ParseProvenance(R"({"grid":{"voxel_size":"0.5"}})").grid);
  EXPECT_EQ(ParseProvenance(R"({"grid":{"resolution":-64,"voxel_size":0.5}})").grid,
            (GridFit{0, 0.5, 0}));
  EXPECT_EQ(ParseProvenance(
                R"({"build":{"bricks":"3","contours":1,"compression":true,"zstd_level":"9"}})")
                .build,
            (BuildSettings{0, false, SvoCompression{false, 3}}));
  EXPECT_EQ(
      ParseProvenance(R"({"voxelize":{"mode":1,"color":"yes","normal":1,"fill":true}})").voxelize,
      (VoxelSettings{VoxelMode::kConservative, false, false, false}));
  EXPECT_EQ(
      ParseProvenance(R"({"bake":{"cones":"5","aperture":"2","jitter_seed":-1,"offset":null}})")
          .bake,
      BakeSettings{});
}

TEST(Provenance, MalformedOrNonObjectJsonIsEmptyNeverAnException) {
  for (const std::string& text : std::vector<std::string>{
           "", " ", "{", R"({"source":)", R"({"source":"a.obj")", "not json", "[1,2,3]",
           R"("a string")", "42", "null", R"({"source":"a.obj"} trailing)", std::string("{\0}", 3),
           "\xFF\xFE"}) {
    SCOPED_TRACE(text);
    Provenance p;
    EXPECT_NO_THROW(p = ParseProvenance(text));
    EXPECT_EQ(p.source, "");
    EXPECT_EQ(p.generator, "");
    EXPECT_EQ(p.triangles, 0u);
    EXPECT_FALSE(p.grid || p.voxelize || p.build || p.bake);
  }
}

TEST(Provenance, ASourceNameThatIsNotUtf8IsEscaped) {
  Provenance p;
  p.source =
      "m\xFF"
      "sh.obj";
  std::string json;
  ASSERT_NO_THROW(json = ProvenanceJson(p));
  EXPECT_NE(json.find(R"("source":"m\\xFFsh.obj")"), std::string::npos) << json;
  EXPECT_EQ(ParseProvenance(json).source, "m\\xFFsh.obj");
  // Valid UTF-8 stays as it is.
  p.source = "Café 模型.obj";
  EXPECT_EQ(ParseProvenance(ProvenanceJson(p)).source, "Café 模型.obj");
}

}  // namespace
}  // namespace svokit
