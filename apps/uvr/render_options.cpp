#include "render_options.h"

#include "core/error.h"
#include "core/timer.h"
#include "engine/render_defaults.h"
#include "io/mesh_io.h"

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
  loaded.mesh = loadMesh(o.mesh, {o.timeStep});
  loaded.loadMs = loadTimer.milliseconds();
  if (loaded.mesh.skippedCells > 0)
    std::fprintf(stderr, "uvr: %s: skipped %llu lower-dimensional cells\n", o.mesh.c_str(),
                 static_cast<unsigned long long>(loaded.mesh.skippedCells));
  loaded.fieldIndex = chooseField(loaded.mesh, o.field, o.mesh);
  return loaded;
}

RenderSettings parseRenderSettings(const RenderOptions &o) {
  RenderSettings settings;
  parseSize(o.size, settings.width, settings.height);
  settings.backend = parseBackend(o.backend);
  settings.background = parseVector(o.background, "background");
  settings.integrator.mode = parseMode(o.mode);
  return settings;
}

IntegratorSettings chooseSampling(const RenderOptions &o, const Mesh &mesh) {
  return samplingSettings(parseMode(o.mode), defaultStepSize(volumeStats(mesh)), o.s1, o.s2, o.p, o.unit);
}

ValueRange transferRange(const RenderOptions &o, const ScalarField &field) {
  return o.range.empty() ? valueRange(field) : ValueRange{o.range[0], o.range[1]};
}

Camera chooseCamera(const RenderOptions &o, const Mesh &mesh) {
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
