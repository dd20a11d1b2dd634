#include "render_options.h"

#include "front_end.h"

#include <uvr/error.h>
#include <uvr/system.h>

#include <cstdio>
#include <sstream>

namespace uvr {

namespace {

Vec3f parseVector(const std::string &text, const std::string &option) {
  Vec3f v;
  char c1 = 0, c2 = 0;
  std::istringstream in(text);
  if (!(in >> v.x >> c1 >> v.y >> c2 >> v.z) || c1 != ',' || c2 != ',' || !in.eof())
    throw Error("--" + option + " expects X,Y,Z, got '" + text + "'");
  return v;
}

void parseSize(const std::string &text, int &width, int &height) {
  char x = 0;
  std::istringstream in(text);
  if (!(in >> width >> x >> height) || x != 'x' || !in.eof() || width <= 0 || height <= 0 || width > 16384 ||
      height > 16384)
    throw Error("--size expects WxH with each side from 1 to 16384, got '" + text + "'");
}

} // namespace

void addRenderOptions(CLI::App *cmd, RenderOptions &o) {
  cmd->add_option("MESH", o.mesh,
                  "Mesh file (.vtu, .vtk, .msh, .e, .ex2, .exo, .g, .umesh; a .pvd series or numbered files "
                  "such as data_%d.vtu)")
      ->required();
  cmd->add_option("--time-step", o.timeStep, "Time step of a file that has several, from 0")
      ->capture_default_str();
  cmd->add_option("--field", o.field, "Scalar field to render (default: the first)");
  cmd->add_option("--tf", o.tf, "Transfer function: a ParaView preset JSON file or a built-in name");
  cmd->add_option("--tf-name", o.tfName, "Preset to take from the --tf file (default: the first)");
  cmd->add_option("--range", o.range, "Scalar range the transfer function spans (default: the field's)")
      ->expected(2);
  cmd->add_option("--mode", o.mode, "reference | skip | adaptive | full")
      ->check(CLI::IsMember({"reference", "skip", "adaptive", "full"}))
      ->capture_default_str();
  cmd->add_option("--compositing", o.compositing,
                  "point | preintegrated | auto (pre-integrated in full, point samples in the other modes)")
      ->check(CLI::IsMember({"auto", "point", "preintegrated"}))
      ->capture_default_str();
  cmd->add_option("--steps", o.steps,
                  "global | local | auto (local in full: each partition's steps scaled to its cells' size)")
      ->check(CLI::IsMember({"auto", "global", "local"}))
      ->capture_default_str();
  cmd->add_option("--s1", o.s1, "Smallest (and fixed) step (default: cube root of the median cell volume)");
  cmd->add_option("--s2", o.s2, "Largest adaptive step (default: 8 * the default s1)");
  cmd->add_option("--p", o.p, "Adaptive power, >= 1 (default: 4)");
  cmd->add_option("--unit", o.unit, "Opacity unit distance (default: the default s1)");
  cmd->add_option("--leaf-size", o.leafSize,
                  "Most cells per partition (default: the cell count / 256, at least 64)");
  cmd->add_option("--size", o.size, "Image size WxH")->capture_default_str();
  cmd->add_option("--eye", o.eye, "Camera position X,Y,Z (default: framing the mesh from +z)");
  cmd->add_option("--at", o.at, "Focal point X,Y,Z (default: the centre of the mesh bounds)");
  cmd->add_option("--up", o.up, "View-up direction X,Y,Z (default: 0,1,0)");
  cmd->add_option("--fovy", o.fovy, "Vertical view angle in degrees")->capture_default_str();
  cmd->add_option("--background", o.background, "Background colour R,G,B in [0, 1]")->capture_default_str();
  cmd->add_option("--backend", o.backend, "cpu or cuda")->capture_default_str();
}

LoadedMesh loadForRendering(const RenderOptions &o) {
  LoadedMesh loaded;
  const Timer loadTimer;
  LoadOptions options;
  options.timeStep = o.timeStep;
  loaded.mesh = VolumeMesh::load(o.mesh, options);
  loaded.loadMs = loadTimer.milliseconds();
  const uint64_t skipped = loaded.mesh.cellCounts().skipped;
  if (skipped > 0)
    std::fprintf(stderr, "uvr: %s: skipped %llu lower-dimensional cells\n", o.mesh.c_str(),
                 static_cast<unsigned long long>(skipped));
  loaded.fieldIndex = loaded.mesh.chooseField(o.field);
  return loaded;
}

FrameSettings parseFrameSettings(const RenderOptions &o) {
  FrameSettings settings;
  parseSize(o.size, settings.width, settings.height);
  settings.backend = parseBackendOption(o.backend);
  settings.background = parseVector(o.background, "background");
  settings.mode = parseMode(o.mode);
  settings.compositing = parseCompositing(o.compositing);
  settings.steps = parseStepSizing(o.steps);
  settings.s1 = o.s1;
  settings.s2 = o.s2;
  settings.p = o.p;
  settings.unit = o.unit;
  return settings;
}

ValueRange transferRange(const RenderOptions &o, const VolumeMesh &mesh, int fieldIndex) {
  return o.range.empty() ? mesh.fieldRange(fieldIndex) : ValueRange{o.range[0], o.range[1]};
}

Camera chooseCamera(const RenderOptions &o, const VolumeMesh &mesh) {
  int width, height;
  parseSize(o.size, width, height);
  Camera camera = frameBounds(mesh.bounds(), o.fovy, float(width) / float(height));
  if (!o.at.empty())
    camera.at = parseVector(o.at, "at");
  if (!o.eye.empty())
    camera.eye = parseVector(o.eye, "eye");
  if (!o.up.empty())
    camera.up = parseVector(o.up, "up");
  checkCamera(camera);
  return camera;
}

} // namespace uvr
