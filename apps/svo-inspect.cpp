// svo-inspect: statistics of a sparse voxel octree (text or JSON), pictures of it rendered by a
// CPU ray caster that honours contours, and slices of its grid.

#include <filesystem>
#include <optional>
#include <vector>

#include "apps/cli.hpp"
#include "apps/run.hpp"
#include "svokit/core/thread_limit.hpp"
#include "svokit/inspect/inspect_svo.hpp"

namespace {

using namespace svokit;

struct InspectCli {
  InspectRequest request;
  std::string view = "front", size = "512x512", shade = "color";
  std::optional<std::string> background;
  bool no_contours = false;
  std::vector<std::string> slice;
  app::MemoryLimitOption memory_limit;

  void Add(CLI::App& cli) {
    app::AddFile(cli, "input", request.input, "Octree (.svo)")->required();
    cli.add_flag("--levels", request.levels, "Add the per-level table");
    cli.add_flag("--histograms", request.histograms,
                 "Add histograms: children per node, brick opacity, contour extent");
    app::AddFile(cli, "--render", request.render_path, "Render the octree to this PNG");
    cli.add_option("--view", view, "The side the render looks from")
        ->option_text("front|back|left|right|top|bottom|iso")
        ->capture_default_str();
    cli.add_option("--size", size, "Render size in pixels")
        ->option_text("WxH")
        ->capture_default_str();
    cli.add_option("--shade", shade, "What the render's pixels show")
        ->option_text("color|normal|depth|ao")
        ->capture_default_str();
    cli.add_option("--background", background,
                   "Where no ray hits: an opaque colour, or none for transparent (default: none; "
                   "334d66 with --shade ao)")
        ->option_text("none|RRGGBB");
    cli.add_flag("--no-contours", no_contours, "Render leaves as full cubes, ignoring contours");
    cli.add_option("--slice", slice, "Write slice K across axis x, y or z of the grid as PNG")
        ->option_text("AXIS=K FILE")
        ->expected(2);
    cli.add_option("--level", request.level,
                   "Read levels 0..L only: statistics cover them, renders and slices show level "
                   "L's nodes as leaves")
        ->option_text("L");
    memory_limit.Add(cli,
                     "Bytes of pages a paged file's statistics, renders and slices hold at once "
                     "(default: a few per thread); --shade ao reads the octree whole");
  }

  // Every option is parsed before the file is read, so a typo costs nothing.
  Status Parse() {
    StatusOr<View> v = ParseView(view);
    if (!v.ok()) return Status::BadInput("--{}", v.status().message());
    StatusOr<Shade> s = ParseShade(shade);
    if (!s.ok()) return Status::BadInput("--{}", s.status().message());
    StatusOr<std::array<int, 2>> wh = ParseImageSize(size);
    if (!wh.ok()) return Status::BadInput("--{}", wh.status().message());
    request.render.view = *v;
    request.render.width = (*wh)[0];
    request.render.height = (*wh)[1];
    request.render.shade = *s;
    request.render.contours = !no_contours;
    if (*s == Shade::kAo) request.render.background = kAoBackground;
    if (background) {
      StatusOr<std::optional<Background>> b = ParseBackground(*background);
      if (!b.ok()) return Status::BadInput("--{}", b.status().message());
      request.render.background = *b;
    }
    StatusOr<std::optional<std::uint64_t>> limit = memory_limit.Bytes();
    if (!limit.ok()) return limit.status();
    request.memory_limit = limit->value_or(0);
    if (slice.empty()) return Status::Ok();
    StatusOr<SliceSpec> spec = ParseSlice(slice[0]);
    if (!spec.ok()) return Status::BadInput("--{}", spec.status().message());
    request.slice = *spec;
    request.slice_path = slice[1];
    return Status::Ok();
  }
};

}  // namespace

int main(int argc, char** argv) {
  const std::string tool = "svo-inspect";
  CLI::App cli{
      "Prints a sparse voxel octree's statistics (header, transform, levels, bricks, contours, "
      "provenance) and renders it (--render) or one slice of its grid (--slice) as PNG.",
      tool};
  InspectCli inspect;
  app::CommonOptions common;
  inspect.Add(cli);
  app::AddCommonOptions(cli, common,
                        "svo-inspect bunny.svo --levels --render bunny.png --view iso");
  return app::Run(tool, cli, argc, argv, inspect.request.input, [&] {
    if (Status s = inspect.Parse(); !s.ok()) return app::Fail(tool, s);
    inspect.request.json = common.json;
    ThreadLimit threads(common.threads);
    Progress progress = common.MakeProgress();
    StatusOr<std::string> report = InspectSvo(inspect.request, progress);
    if (!report.ok()) return app::Fail(tool, report.status());
    if (common.json || !common.quiet) fmt::print("{}", *report);
    return 0;
  });
}
