#include "render_options.h"

#include "front_end.h"
#include "movie.h"
#include "option_checks.h"

#include <uvr/color_map.h>
#include <uvr/error.h>
#include <uvr/renderer.h>
#include <uvr/system.h>

#include <cmath>
#include <cstdio>
#include <sstream>

namespace uvr {

namespace {

Vec3f parseVector(const std::string &text, const std::string &option) {
  Vec3f v;
  char c1 = 0, c2 = 0;
  std::istringstream in(text);
  if (!(in >> v.x >> c1 >> v.y >> c2 >> v.z) || c1 != ',' || c2 != ',' || !in.eof() || !std::isfinite(v.x) ||
      !std::isfinite(v.y) || !std::isfinite(v.z))
    throw Error("--" + option + " expects three finite numbers X,Y,Z, got '" + text + "'");
  return v;
}

std::vector<float> parseIsoValues(const std::string &text) {
  const std::string expected = "--iso expects up to " + std::to_string(kMaxIsoSurfaces) +
                               " finite numbers V[,V...], got '" + text + "'";
  std::vector<float> values;
  std::istringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::istringstream number(item);
    float value;
    if (!(number >> value) || !(number >> std::ws).eof() || !std::isfinite(value))
      throw Error(expected);
    values.push_back(value);
  }
  if (values.empty() || values.size() > kMaxIsoSurfaces || text.back() == ',')
    throw Error(expected);
  return values;
}

void parseSize(const std::string &text, int &width, int &height) {
  char x = 0;
  std::istringstream in(text);
  if (!(in >> width >> x >> height) || x != 'x' || !in.eof() || width <= 0 || height <= 0 || width > 16384 ||
      height > 16384)
    throw Error("--size expects WxH with each side from 1 to 16384, got '" + text + "'");
}

} // namespace

std::string builtinNames() {
  std::string names;
  for (const std::string &name : builtinColorMapNames())
    names += (names.empty() ? "" : ", ") + name;
  return names;
}

std::string viewNames() {
  std::string names;
  for (const std::string &name : cameraViewNames())
    names += (names.empty() ? "" : "|") + name;
  return names;
}

void addRenderOptions(CLI::App *cmd, RenderOptions &o, bool timeRanges) {
  cmd->add_option("MESH", o.mesh,
                  "Mesh file (.vtu, .vtk, .msh, .e, .ex2, .exo, .g, .umesh; a .pvd series or numbered files "
                  "such as data_%d.vtu)")
      ->required();
  if (timeRanges)
    cmd->add_option(
           "--time-step", o.timeSteps,
           "Time step of a file that has several, from 0; A:B[:STEP] (B included) or all: a movie of "
           "those steps")
        ->check(CLI::Validator(
            [](std::string &text) -> std::string {
              try {
                parseTimeSteps(text);
              } catch (const Error &e) {
                return e.what();
              }
              return {};
            },
            "N|A:B[:STEP]|all"))
        ->each([&o](const std::string &text) {
          const TimeSteps steps = parseTimeSteps(text);
          if (!steps.range)
            o.timeStep = steps.first;
        })
        ->default_str("0");
  else
    cmd->add_option("--time-step", o.timeStep, "Time step of a file that has several, from 0")
        ->check(integerAtLeast(0))
        ->capture_default_str();
  cmd->add_option("--field", o.field, "Scalar field to render (default: the first)");
  cmd->add_option("--tf", o.tf,
                  "Transfer function: a ParaView preset JSON file or a built-in name: " + builtinNames());
  cmd->add_option("--tf-name", o.tfName, "Preset to take from the --tf file (default: the first)");
  cmd->add_option("--range", o.range, "Scalar range LO HI the transfer function spans (default: the field's)")
      ->expected(2)
      ->check(finiteNumber());
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
  cmd->add_option("--s1", o.s1,
                  "Smallest (and fixed) step (default: cube root of the median volume per tetrahedron of a "
                  "cell's split)")
      ->check(positiveNumber());
  cmd->add_option("--s2", o.s2, "Largest adaptive step, >= s1 (default: 8 * the default s1)")
      ->check(positiveNumber());
  cmd->add_option("--p", o.p, "Adaptive power, >= 1 (default: 4)")->check(atLeast(1.0, "1"));
  cmd->add_option("--unit", o.unit,
                  "Opacity unit distance (default: the bounds' diagonal / cube root of the cell count)")
      ->check(positiveNumber());
  cmd->add_option("--leaf-size", o.leafSize,
                  "Most cells per partition (default: the cell count / 256, at least 64)")
      ->check(integerAtLeast(1));
  cmd->add_option("--size", o.size, "Image size WxH")->capture_default_str();
  cmd->add_option("--view", o.view,
                  "Side the camera looks from, framing the mesh as ParaView's reset camera: " + viewNames() +
                      " (default: +z)")
      ->check(CLI::IsMember(cameraViewNames()));
  cmd->add_option("--eye", o.eye, "Camera position X,Y,Z (default: framing the mesh from --view)");
  cmd->add_option("--at", o.at, "Focal point X,Y,Z (default: the centre of the mesh bounds)");
  cmd->add_option("--up", o.up, "View-up direction X,Y,Z (default: 0,1,0; 0,0,1 for the x and y views)");
  cmd->add_option("--fovy", o.fovy, "Vertical view angle in degrees, between 0 and 180")
      ->check(numberCheck("a number of degrees between 0 and 180", [](double v) { return v > 0 && v < 180; }))
      ->capture_default_str();
  cmd->add_option("--background", o.background, "Background colour R,G,B, each in [0, 1]")
      ->capture_default_str();
  cmd->add_option("--backend", o.backend, "cpu or cuda")->capture_default_str();
  cmd->add_option_function<std::string>(
         "--memory", [](const std::string &name) { setMemoryLayout(parseMemoryLayout(name)); },
         "auto (default), default or lean: lean keeps no tet adjacency, seed grid or boundary faces and "
         "finds "
         "every sample's cell by the BVH (the same image, slower); auto is lean where the GPU's memory "
         "would not hold the default")
      ->check(CLI::IsMember({"auto", "default", "lean"}));
  cmd->add_flag("--shade", o.shade,
                "Light the volume by the field's gradient (Blinn-Phong: ambient 0.2, diffuse 0.7, specular "
                "0.2, shininess 16)");
  cmd->add_option(
      "--light", o.light,
      "With --shade or --iso, direction towards the light X,Y,Z in camera space: x right, y up, z "
      "towards the viewer (default: a headlight at the eye)");
  cmd->add_option("--iso", o.iso,
                  "Isosurfaces at these field values V[,V...] (at most 8), lit by the field's gradient and "
                  "composited with the volume");
  cmd->add_option("--iso-color", o.isoColor,
                  "Colour R,G,B of the isosurfaces, each in [0, 1] (default: the transfer function's at each "
                  "value)");
  cmd->add_option("--iso-opacity", o.isoOpacity, "Opacity of each isosurface, in (0, 1]")
      ->capture_default_str();
  cmd->add_flag("--iso-only", o.isoOnly, "Draw the isosurfaces alone, the volume hidden");
}

LoadedMesh loadForRendering(const RenderOptions &o) { return loadForRendering(o, o.timeStep); }

LoadedMesh loadForRendering(const RenderOptions &o, int timeStep) {
  LoadedMesh loaded;
  const Timer loadTimer;
  LoadOptions options;
  options.timeStep = timeStep;
  loaded.mesh = VolumeMesh::load(o.mesh, options);
  loaded.loadMs = loadTimer.milliseconds();
  const uint64_t skipped = loaded.mesh.cellCounts().skipped;
  if (skipped > 0)
    std::fprintf(stderr, "uvr: %s: skipped %llu lower-dimensional cells\n", o.mesh.c_str(),
                 static_cast<unsigned long long>(skipped));
  try {
    loaded.fieldIndex = loaded.mesh.chooseField(o.field);
  } catch (const Error &e) {
    throw Error(std::string(e.what()) + (o.field.empty() ? "" : " (--field)"));
  }
  return loaded;
}

void warnOfSmallStep(const FrameSettings &settings, const VolumeMesh &mesh) {
  // The default step takes at most 10^4 along the diagonal; a step given that takes more makes slow frames.
  const Box3f bounds = mesh.bounds();
  const float diagonal = length(bounds.upper - bounds.lower);
  if (settings.s1 > 0.f && diagonal / settings.s1 > 1e4f)
    std::fprintf(
        stderr,
        "uvr: warning: --s1 %g takes %.0f samples along the mesh's diagonal (the default at most 10000)\n",
        double(settings.s1), double(diagonal / settings.s1));
}

FrameSettings parseFrameSettings(const RenderOptions &o) {
  FrameSettings settings;
  parseSize(o.size, settings.width, settings.height);
  try {
    settings.backend = parseBackendOption(o.backend);
  } catch (const Error &e) {
    const std::string what = e.what();
    throw Error(what.find("--backend") == std::string::npos ? what + " (--backend)" : what);
  }
  settings.background = parseVector(o.background, "background");
  for (const float c : {settings.background.x, settings.background.y, settings.background.z})
    if (!(c >= 0.f && c <= 1.f))
      throw Error("--background expects R,G,B each in [0, 1], got '" + o.background + "'");
  settings.shade = o.shade;
  if (o.iso)
    settings.isoValues = parseIsoValues(*o.iso);
  if (!o.light.empty()) {
    settings.light = parseVector(o.light, "light");
    if (!o.shade && !o.iso)
      throw Error("--light needs --shade (or --iso)");
  }
  if (!o.isoColor.empty()) {
    if (!o.iso)
      throw Error("--iso-color needs --iso");
    settings.isoColor = parseVector(o.isoColor, "iso-color");
    for (const float c : {settings.isoColor->x, settings.isoColor->y, settings.isoColor->z})
      if (!(c >= 0.f && c <= 1.f))
        throw Error("--iso-color expects R,G,B each in [0, 1], got '" + o.isoColor + "'");
  }
  if (!(o.isoOpacity > 0.f && o.isoOpacity <= 1.f))
    throw Error("--iso-opacity expects a number in (0, 1], got " + CLI::detail::to_string(o.isoOpacity));
  settings.isoOpacity = o.isoOpacity;
  if (o.isoOnly && !o.iso)
    throw Error("--iso-only needs --iso");
  settings.isoOnly = o.isoOnly;
  settings.mode = parseMode(o.mode);
  settings.compositing = parseCompositing(o.compositing);
  settings.steps = parseStepSizing(o.steps);
  settings.s1 = o.s1;
  settings.s2 = o.s2;
  settings.p = o.p;
  settings.unit = o.unit;
  try {
    validateSettings(settings); // what the validators above leave: s2 below s1
  } catch (const Error &e) {
    throw Error(std::string(e.what()) + " (--s1, --s2)");
  }
  if (!o.range.empty() && !(o.range[0] < o.range[1]))
    throw Error("--range expects LO HI with LO below HI, got " + CLI::detail::to_string(o.range[0]) + " " +
                CLI::detail::to_string(o.range[1]));
  for (const std::string *v : {&o.eye, &o.at, &o.up})
    if (!v->empty())
      parseVector(*v, v == &o.eye ? "eye" : v == &o.at ? "at" : "up");
  return settings;
}

ColorMap chooseTransferFunction(const RenderOptions &o) {
  try {
    return chooseColorMap(o.tf, o.tfName);
  } catch (const Error &e) {
    throw Error(std::string(e.what()) + (o.tfName.empty() ? " (--tf)" : " (--tf, --tf-name)"));
  }
}

ValueRange transferRange(const RenderOptions &o, const VolumeMesh &mesh, int fieldIndex) {
  if (!o.range.empty())
    return {o.range[0], o.range[1]};
  return transferRange(o, mesh.fieldRange(fieldIndex), mesh.field(fieldIndex).name);
}

ValueRange transferRange(const RenderOptions &o, ValueRange data, const std::string &name) {
  if (!o.range.empty())
    return {o.range[0], o.range[1]};
  const ValueRange range = defaultTransferRange(data);
  if (!(data.min < data.max))
    std::fprintf(stderr,
                 "uvr: field '%s' is constant (%g): the transfer function spans [%g, %g]; set --range\n",
                 name.c_str(), double(data.min), double(range.min), double(range.max));
  return range;
}

Camera chooseCamera(const RenderOptions &o, const VolumeMesh &mesh) { return chooseCamera(o, mesh.bounds()); }

Camera chooseCamera(const RenderOptions &o, const Box3f &bounds) {
  int width, height;
  parseSize(o.size, width, height);
  Camera camera = frameBounds(bounds, o.view.empty() ? "+z" : o.view, o.fovy, float(width) / float(height));
  if (!o.at.empty())
    camera.at = parseVector(o.at, "at");
  if (!o.eye.empty())
    camera.eye = parseVector(o.eye, "eye");
  if (!o.up.empty())
    camera.up = parseVector(o.up, "up");
  try {
    validateCamera(camera);
  } catch (const Error &e) {
    throw Error(std::string(e.what()) + " (--view, --eye, --at, --up, --fovy)");
  }
  return camera;
}

} // namespace uvr
