// How a frame is drawn: the sampling mode and steps (paper §2.3-2.4), image size, background and backend.
#pragma once

#include <uvr/vec.h>

#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace uvr {

enum class RenderMode : uint8_t {
  Reference, ///< fixed step s1 over the mesh bounds, nothing skipped
  Skip,      ///< fixed step s1, transparent partitions and empty space skipped
  Adaptive,  ///< step per partition from its colour variance, nothing skipped
  Full       ///< both
};

/// reference, skip, adaptive or full.
const char *modeName(RenderMode mode);
/// Parses reference|skip|adaptive|full; throws uvr::Error otherwise.
RenderMode parseMode(const std::string &name);

/// How the samples along a ray are composited.
enum class Compositing : uint8_t {
  Auto,         ///< pre-integrated in `full`; point samples in the paper's other modes
  Point,        ///< each sample's colour over the distance to the next (the paper's)
  Preintegrated ///< each segment between two samples integrated over the values between them
};

/// auto, point or preintegrated.
const char *compositingName(Compositing compositing);
/// Parses auto|point|preintegrated; throws uvr::Error otherwise.
Compositing parseCompositing(const std::string &name);
/// Whether frames of `mode` composite pre-integrated under `compositing`.
bool preintegrates(Compositing compositing, RenderMode mode);

/// How the step sizes vary over the mesh.
enum class StepSizing : uint8_t {
  Auto,   ///< local in `full`; global in the paper's other modes
  Global, ///< s1 (and s2) alike everywhere (the paper's)
  Local   ///< each partition's steps scaled by its cells' size against the mesh's, by 1/8 to 8 (powers of 2)
};

/// auto, global or local.
const char *stepSizingName(StepSizing sizing);
/// Parses auto|global|local; throws uvr::Error otherwise.
StepSizing parseStepSizing(const std::string &name);
/// Whether frames of `mode` take local steps under `sizing`.
bool stepsFollowMesh(StepSizing sizing, RenderMode mode);

enum class Backend : uint8_t {
  Cpu, ///< all cores
  Cuda ///< one GPU; see backendAvailable
};

/// cpu or cuda.
const char *backendName(Backend backend);
/// Parses cpu|cuda; throws uvr::Error otherwise.
Backend parseBackend(const std::string &name);
/// Whether this build of the library has `backend` (CUDA needs the toolkit at build time; a GPU is then
/// looked for when the backend is first prepared).
bool backendAvailable(Backend backend);

/// What a backend keeps beside the mesh to find each sample's cell (docs/design.md, "GPU memory").
enum class MemoryLayout : uint8_t {
  Auto,    ///< Lean where the CUDA backend's default build would not fit the GPU memory free; else Default
  Default, ///< the tets' adjacency, the seed grid and the boundary faces too: samples walk from the last one
  Lean     ///< without them: every sample's cell is found by the BVH; the same images, slower
};

/// auto, default or lean.
const char *memoryLayoutName(MemoryLayout layout);
/// Parses auto|default|lean; throws uvr::Error otherwise.
MemoryLayout parseMemoryLayout(const std::string &name);

/// The most isosurfaces a frame draws (FrameSettings::isoValues).
constexpr uint32_t kMaxIsoSurfaces = 8;

/// A ray stops once this opaque (early ray termination); what lies behind is taken to have the colour of
/// the last stretch it went through (docs/design.md, "Opacity correction and compositing").
constexpr float kTerminationOpacity = 0.99f;

/// A leaf size that asks for the default: the cell count / 256, at least 64 (about 256 partitions).
constexpr uint32_t kAutoLeafSize = 0;

/// Sampling, image and backend of a frame. A step, power or unit of 0 asks for the mesh's default
/// (withDefaultSampling).
struct FrameSettings {
  RenderMode mode = RenderMode::Full;
  float s1 = 0.f;   ///< smallest (and the fixed) step; default: the mesh's default step
  float s2 = 0.f;   ///< largest adaptive step; default: 8 x the default step, at least s1
  float p = 0.f;    ///< adaptive power, >= 1; default 4
  float unit = 0.f; ///< opacity unit distance; default: defaultUnitDistance of the mesh
  Compositing compositing = Compositing::Auto;
  StepSizing steps = StepSizing::Auto;
  int width = 1024;
  int height = 1024;
  Vec3f background{0.f, 0.f, 0.f}; ///< RGB in [0, 1], under the volume
  Backend backend = Backend::Cpu;
  bool keepImage = true;           ///< return the image composited over the background (FrameResult::image)
  bool keepOpacity = true;         ///< return the accumulated opacity per pixel
  bool keepSamplesPerPixel = true; ///< return the samples taken per pixel
  /// Return the premultiplied colour and opacity per pixel as floats, before the background: what frames of
  /// several pieces of a mesh are composited from.
  bool keepPremultipliedRgba = false;
  /// The same in 16 bits a channel (65535 for 1): a quarter of the bytes, where a 16-bit channel suffices
  /// (frames composited into 8-bit images).
  bool keepPremultipliedRgba16 = false;
  /// Empty, or width x height distances from the eye, row-major, top row first: each pixel's ray ends there
  /// (+inf: it does not), so that opaque geometry drawn by another renderer (its depth buffer converted to
  /// distances) hides the volume behind it. Viewed, not copied: the array must outlive the frame.
  std::span<const float> rayLimits;
  /// Light each sample by the field's gradient (Blinn-Phong, two-sided), blended with the unlit colour by
  /// the gradient's magnitude so that near-uniform regions stay unlit (docs/design.md, "Shading"). The
  /// gradient per point (12 bytes a point) is computed on the host by the first shaded frame.
  bool shade = false;
  /// Towards the light in camera space (x right, y up, z towards the eye; any length); 0,0,0: a headlight
  /// at the eye, whose light comes along each ray.
  Vec3f light{0.f, 0.f, 0.f};
  float ambient = 0.2f, diffuse = 0.7f, specular = 0.2f; ///< Blinn-Phong's coefficients, >= 0
  float shininess = 16.f;                                ///< the specular exponent, >= 1
  /// Field values whose isosurfaces to draw (at most 8, finite): each is found where the field crosses it
  /// along a ray, lit by the field's gradient as its normal (Blinn-Phong from `light`, with or without
  /// `shade`) and composited with the volume at its depth (docs/design.md, "Isosurfaces").
  std::vector<float> isoValues;
  /// Every isosurface's colour, R,G,B in [0, 1]; unset: each takes the transfer function's colour at its
  /// value.
  std::optional<Vec3f> isoColor;
  float isoOpacity = 1.f; ///< of each isosurface, in (0, 1]
  /// Draw the isosurfaces alone: the volume is hidden, and only partitions that hold a surface are marched.
  bool isoOnly = false;
};

/// `settings` with its defaults filled in (0 for s1, s2, p or unit) for a mesh of default step `defaultStep`
/// (VolumeMesh::defaultStep): s1 and unit = defaultStep, s2 = 8 x defaultStep (at least s1), p = 4.
FrameSettings withDefaultSampling(FrameSettings settings, float defaultStep);
/// The same with the opacity unit distance `defaultUnit` (defaultUnitDistance) for a unit of 0: what
/// VolumeRenderer::render uses.
FrameSettings withDefaultSampling(FrameSettings settings, float defaultStep, float defaultUnit);

/// The default opacity unit distance of a mesh, as ParaView derives it from the data set: the length of the
/// bounds' diagonal over the cube root of the cell count (the edge of a mean cell of a cube-shaped mesh), so
/// that the opacity of a preset does not depend on how finely a region is meshed; 1 for an empty mesh.
float defaultUnitDistance(const Box3f &bounds, uint64_t cells);

/// Throws uvr::Error for settings no frame can be drawn with: a negative or non-finite s1, s2, p or unit (0
/// asks for the default), s2 < s1 or p < 1 where both are given, a size outside 1..16384, or a background
/// outside [0, 1], ray limits that are not one non-negative number (or +inf) per pixel, a non-finite light,
/// a negative shading coefficient or a shininess below 1, more than 8 or non-finite isosurface values, an
/// isosurface colour outside [0, 1] or opacity outside (0, 1], or isoOnly without isosurface values. The
/// message names the setting.
void validateSettings(const FrameSettings &settings);

} // namespace uvr
