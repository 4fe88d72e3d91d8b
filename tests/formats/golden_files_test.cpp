// The golden files (formats/golden): each one reads, with today's readers, exactly as its JSON
// records, so a reader that changes what it makes of a file it once wrote fails here; today's
// tools still write each one from its recorded command, so a change of a format fails here too;
// the golden parts merge into the golden build by pages. With SVOKIT_UPDATE_GOLDEN=1 the first
// test writes the JSON instead of comparing it (formats/golden/regenerate).

#include <gtest/gtest.h>

#include <fmt/format.h>

#include <cstdlib>
#include <fstream>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "svokit/formats/container/container.hpp"
#include "svokit/formats/svm/svm.hpp"
#include "svokit/formats/svo/svo_file.hpp"
#include "svokit/formats/vfrag/vfrag.hpp"
#include "svokit/svo/svo_pages.hpp"
#include "tests/formats/golden_dump.hpp"
#include "tests/formats/golden_json.hpp"
#include "tests/test_util.hpp"

namespace svokit::test {
namespace {

std::filesystem::path GoldenDir() {
  return SVOKIT_GOLDEN_DIR;
}

/// One line of formats/golden/commands: a golden file and the command, run in that folder, that
/// writes it; "-" for a file no tool writes any more, kept as it is.
struct GoldenFile {
  std::string name, command;
  bool kept() const { return command == "-"; }
};

std::vector<GoldenFile> Manifest() {
  std::ifstream in(GoldenDir() / "commands");
  std::vector<GoldenFile> files;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream words(line);
    GoldenFile file;
    if (!(words >> file.name) || file.name[0] == '#') continue;
    std::getline(words >> std::ws, file.command);
    files.push_back(file);
  }
  return files;
}

bool Updating() {
  const char* v = std::getenv("SVOKIT_UPDATE_GOLDEN");
  return v != nullptr && *v != '\0' && std::string(v) != "0";
}

/// The formats whose readers are public (a part's reader is svo-merge's).
bool HasJson(const std::string& name) {
  const std::string ext = std::filesystem::path(name).extension().string();
  return ext == ".svm" || ext == ".vfrag" || ext == ".svo";
}

TEST(GoldenFiles, ReadersGiveTheRecordedJson) {
  const std::vector<GoldenFile> files = Manifest();
  ASSERT_FALSE(files.empty()) << "no " << GoldenDir() / "commands";
  for (const GoldenFile& file : files) {
    if (!HasJson(file.name)) continue;
    StatusOr<Json> dump = DumpFormatFile(GoldenDir() / file.name);
    if (!dump.ok()) {
      ADD_FAILURE() << file.name << ": " << dump.status().message();
      continue;
    }
    const std::filesystem::path json_path = GoldenDir() / (file.name + ".json");
    const std::string text = FormatJson(*dump);
    if (Updating()) {
      if (ReadText(json_path) != text) std::ofstream(json_path, std::ios::binary) << text;
      continue;
    }
    const Json recorded = Json::parse(ReadText(json_path), nullptr, false);
    if (recorded.is_discarded()) {
      ADD_FAILURE() << json_path << " is missing or not JSON (formats/golden/regenerate)";
    } else if (const auto difference = FirstDifference(recorded, *dump)) {
      ADD_FAILURE() << file.name << ": the readers differ from " << file.name << ".json at "
                    << *difference;
    }
  }
}

TEST(GoldenFiles, EveryFileIsListed) {
  std::set<std::string> expected = {".gitattributes", "README.md", "commands", "regenerate", "src"};
  for (const GoldenFile& file : Manifest()) {
    EXPECT_TRUE(std::filesystem::exists(GoldenDir() / file.name)) << file.name;
    expected.insert(file.name);
    if (HasJson(file.name)) expected.insert(file.name + ".json");
  }
  for (const auto& entry : std::filesystem::directory_iterator(GoldenDir())) {
    EXPECT_TRUE(expected.contains(entry.path().filename().string()))
        << entry.path() << " is not in formats/golden/commands";
  }
}

TEST(GoldenFiles, ReadmeGivesEveryCommand) {
  const std::string readme = ReadText(GoldenDir() / "README.md");
  for (const GoldenFile& file : Manifest()) {
    if (file.kept()) continue;
    EXPECT_NE(readme.find(file.command), std::string::npos) << file.command;
  }
}

// Every reader of a format makes the same of a golden file: the lenient .svo reader the strict
// one's octree without an issue, the cube-by-cube .vfrag reader (the newest version's) the whole
// one's voxels.
TEST(GoldenFiles, ReadersOfOneFormatAgree) {
  for (const GoldenFile& file : Manifest()) {
    const std::filesystem::path path = GoldenDir() / file.name;
    SCOPED_TRACE(file.name);
    if (path.extension() == ".svo") {
      StatusOr<Svo> strict = ReadSvo(path);
      StatusOr<LenientSvo> lenient = ReadSvoLenient(path);
      ASSERT_TRUE(strict.ok()) << strict.status().message();
      ASSERT_TRUE(lenient.ok()) << lenient.status().message();
      EXPECT_TRUE(lenient->issues.empty()) << lenient->issues.front().message;
      EXPECT_TRUE(lenient->complete);
      EXPECT_TRUE(lenient->svo == *strict);
    } else if (path.extension() == ".vfrag") {
      StatusOr<container::Frame> frame = container::Frame::Open(path, kVfragFormat);
      ASSERT_TRUE(frame.ok()) << frame.status().message();
      if (frame->version() != kVfragFormat.version) continue;
      StatusOr<VoxelSet> whole = ReadVfrag(path);
      ASSERT_TRUE(whole.ok()) << whole.status().message();
      StatusOr<std::unique_ptr<VfragCubes>> cubes = VfragCubes::Open(path, kPageSideBits);
      ASSERT_TRUE(cubes.ok()) << cubes.status().message();
      const auto& d = whole->grid.dims();
      StatusOr<VoxelSet> read =
          (*cubes)->Read({{0, 0, 0}, {std::int64_t{d[0]}, std::int64_t{d[1]}, std::int64_t{d[2]}}});
      ASSERT_TRUE(read.ok()) << read.status().message();
      EXPECT_TRUE(read->keys == whole->keys);
      EXPECT_EQ(read->has_colors(), whole->has_colors());
      for (std::size_t i = 0; i < whole->size() && whole->has_colors(); ++i) {
        ASSERT_TRUE(read->color(i) == whole->color(i)) << "voxel " << i;
      }
      EXPECT_TRUE(read->normals == whole->normals);
      EXPECT_TRUE(read->coverage == whole->coverage);
    }
  }
}

// A version-1 file made from a version-2 one (svo-v1-writer) assembles into the same octree: the
// bricks a version-2 reader assembles are version 1's, byte for byte.
TEST(GoldenFiles, VersionOneAndTwoReadAsOneOctree) {
  int pairs = 0;
  for (const GoldenFile& file : Manifest()) {
    std::istringstream words(file.command);
    std::string tool, source;
    if (!(words >> tool >> source) || tool != "svo-v1-writer") continue;
    ++pairs;
    StatusOr<Json> v1 = DumpFormatFile(GoldenDir() / file.name);
    StatusOr<Json> v2 = DumpFormatFile(GoldenDir() / source);
    ASSERT_TRUE(v1.ok()) << v1.status().message();
    ASSERT_TRUE(v2.ok()) << v2.status().message();
    EXPECT_EQ((*v1)["container"]["version"], 1);
    EXPECT_EQ((*v2)["container"]["version"], 2);
    for (const char* key : {"grid", "meta", "levels"}) {
      const auto difference = FirstDifference((*v2)[key], (*v1)[key]);
      EXPECT_FALSE(difference) << file.name << " against " << source << ": /" << key
                               << difference.value_or("");
    }
  }
  EXPECT_GT(pairs, 0);
}

// A container of any version of the format named by the file's extension: the comparisons below
// read the frame only.
container::FormatId AnyVersion(const std::filesystem::path& path) {
  const std::string ext = path.extension().string();
  container::FormatId format = ext == ".svm"     ? kSvmFormat
                               : ext == ".vfrag" ? kVfragFormat
                                                 : kSvoFormat;
  if (ext == ".svopart") format.magic[3] = 'P';  // \x89SVP: the part file's magic
  format.version = ~std::uint32_t{0};
  return format;
}

// Bytes a file of the format derives from META: the part's identity holds META's CRC-32C in its
// low half (formats/svopart.md, `PART`), so a new tool version changes them.
bool DerivedFromMeta(const container::Tag& tag, std::uint64_t at) {
  return tag == container::MakeTag("PART") && at >= 8 && at < 12;
}

// The first difference between two files of one format, META aside: version, flags, the sections'
// tags in order and every other section's bytes.
std::optional<std::string> DifferenceButMeta(const std::filesystem::path& expected,
                                             const std::filesystem::path& actual) {
  StatusOr<container::Frame> a = container::Frame::Open(expected, AnyVersion(expected));
  StatusOr<container::Frame> b = container::Frame::Open(actual, AnyVersion(expected));
  if (!a.ok()) return a.status().message();
  if (!b.ok()) return b.status().message();
  if (a->version() != b->version() || a->flags() != b->flags()) {
    return fmt::format("version {} flags {} instead of version {} flags {}", b->version(),
                       b->flags(), a->version(), a->flags());
  }
  const auto tags = [](const container::Frame& f) {
    std::string out;
    for (const auto& s : f.sections()) out += std::string(s.tag.begin(), s.tag.end()) + " ";
    return out;
  };
  if (tags(*a) != tags(*b)) return "sections " + tags(*b) + "instead of " + tags(*a);
  for (std::size_t i = 0; i < a->sections().size(); ++i) {
    const container::Frame::Section& x = a->sections()[i];
    const container::Frame::Section& y = b->sections()[i];
    if (x.tag == container::MakeTag("META")) continue;
    const std::string tag(x.tag.begin(), x.tag.end());
    for (std::uint64_t at = 0; at < std::min(x.bytes.size(), y.bytes.size()); ++at) {
      if (x.bytes[at] != y.bytes[at] && !DerivedFromMeta(x.tag, at)) {
        return fmt::format("section {} differs at byte {} (of {})", tag, at, x.bytes.size());
      }
    }
    if (x.bytes.size() != y.bytes.size()) {
      return fmt::format("section {} has {} bytes instead of {}", tag, y.bytes.size(),
                         x.bytes.size());
    }
  }
  return std::nullopt;
}

// META as JSON without "generator", the tool version that every release changes.
Json MetaButGenerator(const std::filesystem::path& path) {
  StatusOr<container::Frame> frame = container::Frame::Open(path, AnyVersion(path));
  if (!frame.ok()) return frame.status().message();
  const container::Frame::Section* meta = frame->Find(container::MakeTag("META"));
  if (meta == nullptr) return nullptr;
  Json json = Json::parse(meta->bytes.begin(), meta->bytes.end(), nullptr, false);
  if (json.is_discarded()) return std::string(meta->bytes.begin(), meta->bytes.end());
  if (json.is_object()) json.erase("generator");
  return json;
}

// Runs `command` in `dir` with the build's tools first on PATH; the error and the tool's output
// if it fails, else "".
std::string RunTool(const std::string& command, const std::filesystem::path& dir,
                    const std::filesystem::path& log) {
  const std::string line =
      fmt::format("cd '{}' && PATH='{}:{}':\"$PATH\" {} < /dev/null > '{}' 2>&1", dir.string(),
                  SVOKIT_BIN_DIR, SVOKIT_TEST_BIN_DIR, command, log.string());
  if (std::system(line.c_str()) == 0) return "";
  return "`" + command + "` failed:\n" + ReadText(log);
}

// The golden files made again by their commands, once for the tests of this suite, in a copy of
// the folder's surroundings (the commands name ../../data and src/).
class GoldenFilesRemade : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = std::make_unique<TempDir>();
    dir_ = root_->path() / "formats" / "golden";
    std::filesystem::create_directories(dir_);
    std::filesystem::create_directory_symlink(DataDir(), root_->path() / "data");
    std::filesystem::create_directory_symlink(GoldenDir() / "src", dir_ / "src");
    failure_.clear();
    // A kept file may be a command's input (a version-2 file baked): it is there as it is.
    for (const GoldenFile& file : Manifest()) {
      if (file.kept()) std::filesystem::copy_file(GoldenDir() / file.name, dir_ / file.name);
    }
    for (const GoldenFile& file : Manifest()) {
      if (file.kept()) continue;
      if (std::string error = RunTool(file.command, dir_, root_->path() / "log"); !error.empty()) {
        failure_ = file.name + ": " + error;
        return;
      }
    }
  }
  static void TearDownTestSuite() { root_.reset(); }

  static std::unique_ptr<TempDir> root_;
  static std::filesystem::path dir_;
  static std::string failure_;
};
std::unique_ptr<TempDir> GoldenFilesRemade::root_;
std::filesystem::path GoldenFilesRemade::dir_;
std::string GoldenFilesRemade::failure_;

// A difference here is a change of what a tool writes: if it is meant (a new version, a new
// section), keep the old files as they are (command "-") and add new ones (README.md).
TEST_F(GoldenFilesRemade, ToolsStillWriteThemButMeta) {
  ASSERT_TRUE(failure_.empty()) << failure_;
  for (const GoldenFile& file : Manifest()) {
    if (file.kept()) continue;
    if (auto difference = DifferenceButMeta(GoldenDir() / file.name, dir_ / file.name)) {
      ADD_FAILURE() << file.name << " is no longer what `" << file.command
                    << "` writes: " << *difference;
    }
  }
}

// META apart, as it records options and provenance as text that is still to become typed JSON:
// when it changes on purpose, formats/golden/regenerate makes the files and their JSON again.
TEST_F(GoldenFilesRemade, ToolsStillRecordTheirMeta) {
  ASSERT_TRUE(failure_.empty()) << failure_;
  for (const GoldenFile& file : Manifest()) {
    if (file.kept()) continue;
    const Json recorded = MetaButGenerator(GoldenDir() / file.name);
    if (auto difference = FirstDifference(recorded, MetaButGenerator(dir_ / file.name))) {
      ADD_FAILURE() << file.name << ": `" << file.command
                    << "` records another META: " << *difference;
    }
  }
}

// The golden parts of a build by pages, merged by today's svo-merge (the reader of parts), are that
// build's golden file.
TEST(GoldenFiles, PartsMergeIntoTheBuildByPages) {
  const TempDir dir;
  const std::string merge = fmt::format("svo-merge '{}' '{}' -o merged.svo",
                                        (GoldenDir() / "pair-r130.part1.svopart").string(),
                                        (GoldenDir() / "pair-r130.part0.svopart").string());
  ASSERT_EQ(RunTool(merge, dir.path(), dir / "log"), "");
  EXPECT_TRUE(ReadBytes(dir / "merged.svo") == ReadBytes(GoldenDir() / "pair-r130-pages.svo"));
}

}  // namespace
}  // namespace svokit::test
