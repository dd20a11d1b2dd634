#include "commands.h"
#include "render_options.h"

#include "front_end.h"

#include <uvr/color_map.h>
#include <uvr/error.h>

#ifdef UVR_HAS_VIEWER
#include "viewer.h"
#endif

#include <filesystem>
#include <memory>

namespace uvr {

namespace {

struct ViewCommandOptions {
  RenderOptions view;
  std::string script;
  std::string screenshot;
};

void runView(const ViewCommandOptions &o) {
  const FrameSettings settings = parseFrameSettings(o.view);
  const ColorMap colorMap = chooseTransferFunction(o.view);
  if (!o.script.empty()) {
    std::error_code error;
    if (!std::filesystem::is_regular_file(o.script, error))
      throw Error(o.script, "", "--script: no such file");
  }
  if (!o.screenshot.empty())
    checkOutputPath(o.screenshot + "-check.png", "--screenshot");
#ifdef UVR_HAS_VIEWER
  const LoadedMesh loaded = loadForRendering(o.view);

  ViewerSetup setup;
  setup.mesh = loaded.mesh;
  setup.meshPath = o.view.mesh;
  setup.fieldIndex = loaded.fieldIndex;
  setup.leafSize = o.view.leafSize;
  setup.defaultStep = loaded.mesh.defaultStep();
  setup.defaultUnit = defaultUnitDistance(loaded.mesh.bounds(), loaded.mesh.cellCount());
  setup.camera = chooseCamera(o.view, loaded.mesh);
  setup.settings = withDefaultSampling(settings, setup.defaultStep, setup.defaultUnit);
  setup.colorMap = colorMap;
  std::error_code tfError; // exists() without it throws for e.g. a name too long
  if (!o.view.tf.empty() && std::filesystem::exists(o.view.tf, tfError))
    setup.presets = readColorMapPresets(o.view.tf);
  setup.range = transferRange(o.view, loaded.mesh, loaded.fieldIndex);
  setup.script = o.script;
  setup.screenshotPrefix = o.screenshot;
  runViewer(setup);
#else
  (void)settings;
  (void)colorMap;
  throw Error("this build of uvr has no viewer: it needs GLFW, OpenGL and Dear ImGui at build time "
              "(Debian: libglfw3-dev libimgui-dev)");
#endif
}

} // namespace

void addViewCommand(CLI::App &app) {
  auto options = std::make_shared<ViewCommandOptions>();
  ViewCommandOptions &o = *options;
  o.view.size = "800x800";
  CLI::App *cmd = app.add_subcommand("view", "Explore a mesh in a window");
  addRenderOptions(cmd, o.view);
  cmd->add_option("--script", o.script,
                  "Replay camera moves and transfer-function edits from a file (docs/cli.md)");
  cmd->add_option("--screenshot", o.screenshot, "Prefix of the PNGs the script's screenshot commands write");
  cmd->callback([options] { runView(*options); });
}

} // namespace uvr
