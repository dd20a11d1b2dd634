// Transfer-function presets. Colours are interpolated as VTK's vtkColorTransferFunction does it and opacity
// as vtkPiecewiseFunction does it, so a preset looks here as it does in ParaView.
#include "core/color_map.h"

#include <uvr/error.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <numbers>
#include <optional>
#include <sstream>

namespace uvr {

namespace {

using Triple = std::array<double, 3>;

enum class ColorSpace { RGB, HSV, Lab, Diverging, Step };

std::string lowercase(std::string text) {
  for (char &c : text)
    c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return text;
}

// ParaView's names; "CIELAB" is the name in its older XML presets. VTK finds a CIEDE2000-shortest path
// between the nodes for "Lab/CIEDE2000"; that search is not implemented, such presets interpolate in plain
// Lab.
std::optional<ColorSpace> parseColorSpace(const std::string &name) {
  const std::string key = lowercase(name);
  if (key == "rgb")
    return ColorSpace::RGB;
  if (key == "hsv")
    return ColorSpace::HSV;
  if (key == "lab" || key == "cielab" || key == "lab/ciede2000")
    return ColorSpace::Lab;
  if (key == "diverging")
    return ColorSpace::Diverging;
  if (key == "step")
    return ColorSpace::Step;
  return std::nullopt;
}

constexpr const char *kColorSpaceNames = "RGB, HSV, Lab, CIELAB, Diverging, Lab/CIEDE2000 or Step";

// --- Colour spaces, with the constants of vtkMath (sRGB primaries, D65 white, CIE 1976 L*a*b*) ---

Triple rgbToLab(const Triple &rgb) {
  Triple linear;
  for (int i = 0; i < 3; ++i)
    linear[i] = rgb[i] > 0.04045 ? std::pow((rgb[i] + 0.055) / 1.055, 2.4) : rgb[i] / 12.92;
  const Triple xyz = {linear[0] * 0.4124 + linear[1] * 0.3576 + linear[2] * 0.1805,
                      linear[0] * 0.2126 + linear[1] * 0.7152 + linear[2] * 0.0722,
                      linear[0] * 0.0193 + linear[1] * 0.1192 + linear[2] * 0.9505};
  constexpr Triple white = {0.9505, 1.0, 1.089};
  Triple f;
  for (int i = 0; i < 3; ++i) {
    const double t = xyz[i] / white[i];
    f[i] = t > 0.008856 ? std::cbrt(t) : 7.787 * t + 16.0 / 116.0;
  }
  return {116.0 * f[1] - 16.0, 500.0 * (f[0] - f[1]), 200.0 * (f[1] - f[2])};
}

Triple labToRgb(const Triple &lab) {
  const double fy = (lab[0] + 16.0) / 116.0;
  const Triple f = {lab[1] / 500.0 + fy, fy, fy - lab[2] / 200.0};
  constexpr Triple white = {0.9505, 1.0, 1.089};
  Triple xyz;
  for (int i = 0; i < 3; ++i) {
    const double cube = f[i] * f[i] * f[i];
    xyz[i] = white[i] * (cube > 0.008856 ? cube : (f[i] - 16.0 / 116.0) / 7.787);
  }
  Triple rgb = {xyz[0] * 3.2406 - xyz[1] * 1.5372 - xyz[2] * 0.4986,
                -xyz[0] * 0.9689 + xyz[1] * 1.8758 + xyz[2] * 0.0415,
                xyz[0] * 0.0557 - xyz[1] * 0.2040 + xyz[2] * 1.0570};
  for (double &c : rgb)
    c = c > 0.0031308 ? 1.055 * std::pow(c, 1.0 / 2.4) - 0.055 : 12.92 * c;
  // Out of gamut: scale down to keep the hue, then drop negatives (as vtkMath::XYZToRGB does).
  const double largest = std::max({rgb[0], rgb[1], rgb[2]});
  for (double &c : rgb)
    c = std::max(largest > 1.0 ? c / largest : c, 0.0);
  return rgb;
}

// Hue, saturation and value all in [0, 1].
Triple rgbToHsv(const Triple &rgb) {
  const double high = std::max({rgb[0], rgb[1], rgb[2]});
  const double low = std::min({rgb[0], rgb[1], rgb[2]});
  const double saturation = high > 0.0 ? (high - low) / high : 0.0;
  if (saturation <= 0.0)
    return {0.0, 0.0, high};
  const double range = high - low;
  double hue;
  if (rgb[0] == high)
    hue = (rgb[1] - rgb[2]) / (6.0 * range);
  else if (rgb[1] == high)
    hue = 1.0 / 3.0 + (rgb[2] - rgb[0]) / (6.0 * range);
  else
    hue = 2.0 / 3.0 + (rgb[0] - rgb[1]) / (6.0 * range);
  return {hue < 0.0 ? hue + 1.0 : hue, saturation, high};
}

Triple hsvToRgb(const Triple &hsv) {
  const double h = 6.0 * hsv[0];
  // The fully saturated colour of this hue, then mixed with white by the saturation and scaled by the value.
  const Triple pure = {std::clamp(std::abs(h - 3.0) - 1.0, 0.0, 1.0),
                       std::clamp(2.0 - std::abs(h - 2.0), 0.0, 1.0),
                       std::clamp(2.0 - std::abs(h - 4.0), 0.0, 1.0)};
  Triple rgb;
  for (int i = 0; i < 3; ++i)
    rgb[i] = hsv[2] * (hsv[1] * pure[i] + 1.0 - hsv[1]);
  return rgb;
}

// Moreland's Msh: polar L*a*b* (magnitude, saturation angle, hue angle), for diverging maps.
Triple labToMsh(const Triple &lab) {
  const double m = std::sqrt(lab[0] * lab[0] + lab[1] * lab[1] + lab[2] * lab[2]);
  const double s = m > 0.001 ? std::acos(lab[0] / m) : 0.0;
  const double h = s > 0.001 ? std::atan2(lab[2], lab[1]) : 0.0;
  return {m, s, h};
}

Triple mshToLab(const Triple &msh) {
  return {msh[0] * std::cos(msh[1]), msh[0] * std::sin(msh[1]) * std::cos(msh[2]),
          msh[0] * std::sin(msh[1]) * std::sin(msh[2])};
}

double angleBetween(double a, double b) {
  constexpr double twoPi = 2.0 * std::numbers::pi;
  const double difference = std::fmod(std::abs(a - b), twoPi);
  return difference > std::numbers::pi ? twoPi - difference : difference;
}

// A hue for an unsaturated colour of magnitude `unsaturatedM` next to the saturated `msh`: spun so that the
// perceptual change along the interpolation stays about constant (Moreland 2009).
double adjustHue(const Triple &msh, double unsaturatedM) {
  if (msh[0] >= unsaturatedM - 0.1)
    return msh[2];
  const double spin =
      msh[1] * std::sqrt(unsaturatedM * unsaturatedM - msh[0] * msh[0]) / (msh[0] * std::sin(msh[1]));
  // Spin away from red, except for purples.
  return msh[2] > -0.3 * std::numbers::pi ? msh[2] + spin : msh[2] - spin;
}

Triple interpolateDiverging(double s, const Triple &rgb1, const Triple &rgb2) {
  Triple msh1 = labToMsh(rgbToLab(rgb1));
  Triple msh2 = labToMsh(rgbToLab(rgb2));
  // Two distinct saturated ends: pass through a neutral white halfway.
  if (msh1[1] > 0.05 && msh2[1] > 0.05 && angleBetween(msh1[2], msh2[2]) > 0.33 * std::numbers::pi) {
    const double whiteM = std::max({msh1[0], msh2[0], 88.0});
    if (s < 0.5) {
      msh2 = {whiteM, 0.0, 0.0};
      s *= 2.0;
    } else {
      msh1 = {whiteM, 0.0, 0.0};
      s = 2.0 * s - 1.0;
    }
  }
  // An unsaturated end has no meaningful hue; borrow one from the other end.
  if (msh1[1] < 0.05 && msh2[1] > 0.05)
    msh1[2] = adjustHue(msh2, msh1[0]);
  else if (msh2[1] < 0.05 && msh1[1] > 0.05)
    msh2[2] = adjustHue(msh1, msh2[0]);
  // Unlike VTK, take the shorter way round: hues on either side of +-pi (the teal middle of viridis) would
  // otherwise sweep through red.
  if (msh1[2] - msh2[2] > std::numbers::pi)
    msh2[2] += 2.0 * std::numbers::pi;
  else if (msh2[2] - msh1[2] > std::numbers::pi)
    msh1[2] += 2.0 * std::numbers::pi;
  Triple msh;
  for (int i = 0; i < 3; ++i)
    msh[i] = (1.0 - s) * msh1[i] + s * msh2[i];
  return labToRgb(mshToLab(msh));
}

Triple lerp(double s, const Triple &a, const Triple &b) {
  return {(1.0 - s) * a[0] + s * b[0], (1.0 - s) * a[1] + s * b[1], (1.0 - s) * a[2] + s * b[2]};
}

// Colour at the normalised position s in [0, 1] between two nodes. RGBPoints carry no midpoint or sharpness,
// so VTK's defaults (0.5, 0) apply and s is used as is.
Triple interpolateColor(ColorSpace space, double s, const Triple &rgb1, const Triple &rgb2) {
  switch (space) {
  case ColorSpace::RGB:
    return lerp(s, rgb1, rgb2);
  case ColorSpace::HSV: {
    Triple hsv1 = rgbToHsv(rgb1);
    Triple hsv2 = rgbToHsv(rgb2);
    // Go round the shorter way of the hue circle.
    if (std::abs(hsv1[0] - hsv2[0]) > 0.5)
      (hsv1[0] > hsv2[0] ? hsv1[0] : hsv2[0]) -= 1.0;
    Triple hsv = lerp(s, hsv1, hsv2);
    if (hsv[0] < 0.0)
      hsv[0] += 1.0;
    return hsvToRgb(hsv);
  }
  case ColorSpace::Lab:
    return labToRgb(lerp(s, rgbToLab(rgb1), rgbToLab(rgb2)));
  case ColorSpace::Diverging:
    return interpolateDiverging(s, rgb1, rgb2);
  case ColorSpace::Step:
    // Each node's colour holds over the interval that ends at it, as VTK_CTF_STEP.
    return rgb2;
  }
  return rgb1;
}

// --- Evaluation between control points (4 floats per point, x first) ---

// Index of the first point with x >= `x`, for x strictly inside (first x, last x]; never 0.
size_t segmentEnd(const std::vector<float> &points, double x) {
  size_t low = 1, high = points.size() / 4 - 1;
  while (low < high) {
    const size_t mid = (low + high) / 2;
    if (points[4 * mid] < x)
      low = mid + 1;
    else
      high = mid;
  }
  return low;
}

Triple colorAt(const std::vector<float> &rgbPoints, ColorSpace space, double x) {
  const auto node = [&](size_t i) -> Triple {
    return {rgbPoints[4 * i + 1], rgbPoints[4 * i + 2], rgbPoints[4 * i + 3]};
  };
  const size_t count = rgbPoints.size() / 4;
  // Outside the nodes the end colours hold (VTK's Clamping on).
  if (x <= rgbPoints.front())
    return node(0);
  if (x > rgbPoints[4 * (count - 1)])
    return node(count - 1);
  const size_t i = segmentEnd(rgbPoints, x);
  const double x1 = rgbPoints[4 * (i - 1)], x2 = rgbPoints[4 * i];
  return interpolateColor(space, (x - x1) / (x2 - x1), node(i - 1), node(i));
}

// vtkPiecewiseFunction's curve: the midpoint is where the value is halfway between the nodes; sharpness 0 is
// linear, 1 a step at the midpoint, and in between a Hermite curve whose end slopes flatten with sharpness.
double opacityAt(const std::vector<float> &points, double x) {
  const size_t count = points.size() / 4;
  if (x <= points.front())
    return points[1];
  if (x > points[4 * (count - 1)])
    return points[4 * (count - 1) + 1];
  const size_t i = segmentEnd(points, x);
  const double x1 = points[4 * (i - 1)], x2 = points[4 * i];
  const double y1 = points[4 * (i - 1) + 1], y2 = points[4 * i + 1];
  // The left node's midpoint and sharpness shape the segment; keep the midpoint off the ends to avoid 0 / 0.
  const double midpoint = std::clamp(double(points[4 * (i - 1) + 2]), 1e-5, 1.0 - 1e-5);
  const double sharpness = points[4 * (i - 1) + 3];

  double s = (x - x1) / (x2 - x1);
  s = s < midpoint ? 0.5 * s / midpoint : 0.5 + 0.5 * (s - midpoint) / (1.0 - midpoint);
  if (sharpness > 0.99)
    return s < 0.5 ? y1 : y2;
  if (sharpness < 0.01)
    return (1.0 - s) * y1 + s * y2;

  // Pull s towards the nearer end, more so the sharper, then a Hermite curve with equal end tangents.
  const double power = 1.0 + 10.0 * sharpness;
  if (s < 0.5)
    s = 0.5 * std::pow(2.0 * s, power);
  else if (s > 0.5)
    s = 1.0 - 0.5 * std::pow(2.0 * (1.0 - s), power);
  const double ss = s * s, sss = ss * s;
  const double h1 = 2.0 * sss - 3.0 * ss + 1.0;
  const double h2 = -2.0 * sss + 3.0 * ss;
  const double h3 = sss - 2.0 * ss + s;
  const double h4 = sss - ss;
  const double tangent = (1.0 - sharpness) * (y2 - y1);
  const double y = h1 * y1 + h2 * y2 + (h3 + h4) * tangent;
  return std::clamp(y, std::min(y1, y2), std::max(y1, y2));
}

// --- Checks shared by the reader and the sampler ---

// Throws unless `points` holds whole points (4 values each) in non-decreasing x.
void checkPoints(const std::vector<float> &points, const char *key, const std::string &file,
                 const std::string &position) {
  if (points.size() % 4 != 0)
    throw Error(file, position,
                std::string(key) + " has " + std::to_string(points.size()) +
                    " values, not a multiple of 4 (" +
                    (std::string(key) == "RGBPoints" ? "x, r, g, b" : "x, opacity, midpoint, sharpness") +
                    " per point)");
  for (size_t i = 4; i < points.size(); i += 4)
    if (points[i] < points[i - 4]) {
      std::ostringstream what;
      what << key << " x values must not decrease, but point " << i / 4 << " has x = " << points[i]
           << " after x = " << points[i - 4];
      throw Error(file, position, what.str());
    }
}

ColorSpace checkedColorSpace(const ColorMap &map, const std::string &file, const std::string &position) {
  if (map.rgbPoints.empty())
    throw Error(file, position, "the preset has no RGBPoints");
  checkPoints(map.rgbPoints, "RGBPoints", file, position);
  checkPoints(map.opacityPoints, "Points", file, position);
  for (size_t i = 0; i < map.opacityPoints.size(); i += 4) {
    const float midpoint = map.opacityPoints[i + 2], sharpness = map.opacityPoints[i + 3];
    if (!(midpoint >= 0.f && midpoint <= 1.f && sharpness >= 0.f && sharpness <= 1.f))
      throw Error(file, position,
                  "Points point " + std::to_string(i / 4) + " has a midpoint or sharpness outside [0, 1]");
  }
  const std::optional<ColorSpace> space = parseColorSpace(map.colorSpace);
  if (!space)
    throw Error(file, position,
                "unknown ColorSpace \"" + map.colorSpace + "\" (expected " + kColorSpaceNames + ")");
  return *space;
}

// --- Built-in presets ---

// Every fifth entry of matplotlib's 256-entry tables (_cm_listed.py, CC0, by Nathaniel J. Smith and Stefan
// van der Walt), so the control points at x = k / 51 reproduce the published colours exactly.
constexpr float kViridis[][3] = {
    {0.267004f, 0.004874f, 0.329415f}, {0.273809f, 0.031497f, 0.358853f}, {0.278791f, 0.062145f, 0.386592f},
    {0.281924f, 0.089666f, 0.412415f}, {0.283197f, 0.11568f, 0.436115f},  {0.282623f, 0.140926f, 0.457517f},
    {0.280255f, 0.165693f, 0.476498f}, {0.276194f, 0.190074f, 0.493001f}, {0.270595f, 0.214069f, 0.507052f},
    {0.263663f, 0.237631f, 0.518762f}, {0.255645f, 0.260703f, 0.528312f}, {0.246811f, 0.283237f, 0.535941f},
    {0.237441f, 0.305202f, 0.541921f}, {0.227802f, 0.326594f, 0.546532f}, {0.21813f, 0.347432f, 0.550038f},
    {0.208623f, 0.367752f, 0.552675f}, {0.19943f, 0.387607f, 0.554642f},  {0.190631f, 0.407061f, 0.556089f},
    {0.182256f, 0.426184f, 0.55712f},  {0.174274f, 0.445044f, 0.557792f}, {0.166617f, 0.463708f, 0.558119f},
    {0.159194f, 0.482237f, 0.558073f}, {0.151918f, 0.500685f, 0.557587f}, {0.144759f, 0.519093f, 0.556572f},
    {0.13777f, 0.537492f, 0.554906f},  {0.131172f, 0.555899f, 0.552459f}, {0.125394f, 0.574318f, 0.549086f},
    {0.121148f, 0.592739f, 0.544641f}, {0.119423f, 0.611141f, 0.538982f}, {0.12138f, 0.629492f, 0.531973f},
    {0.128087f, 0.647749f, 0.523491f}, {0.14021f, 0.665859f, 0.513427f},  {0.157851f, 0.683765f, 0.501686f},
    {0.180653f, 0.701402f, 0.488189f}, {0.20803f, 0.718701f, 0.472873f},  {0.239374f, 0.735588f, 0.455688f},
    {0.274149f, 0.751988f, 0.436601f}, {0.311925f, 0.767822f, 0.415586f}, {0.35236f, 0.783011f, 0.392636f},
    {0.395174f, 0.797475f, 0.367757f}, {0.440137f, 0.811138f, 0.340967f}, {0.487026f, 0.823929f, 0.312321f},
    {0.535621f, 0.835785f, 0.281908f}, {0.585678f, 0.846661f, 0.249897f}, {0.636902f, 0.856542f, 0.21662f},
    {0.688944f, 0.865448f, 0.182725f}, {0.741388f, 0.873449f, 0.149561f}, {0.79376f, 0.880678f, 0.120005f},
    {0.845561f, 0.887322f, 0.099702f}, {0.89632f, 0.893616f, 0.096335f},  {0.945636f, 0.899815f, 0.112838f},
    {0.993248f, 0.906157f, 0.143936f},
};

constexpr float kInferno[][3] = {
    {0.001462f, 0.000466f, 0.013866f}, {0.007676f, 0.006136f, 0.046836f}, {0.019373f, 0.015133f, 0.088767f},
    {0.037668f, 0.025921f, 0.132232f}, {0.06134f, 0.03659f, 0.177642f},   {0.087411f, 0.044556f, 0.224813f},
    {0.116656f, 0.047574f, 0.272321f}, {0.149073f, 0.045468f, 0.317085f}, {0.183429f, 0.040329f, 0.354971f},
    {0.217949f, 0.036615f, 0.383522f}, {0.25162f, 0.037705f, 0.403378f},  {0.284321f, 0.043933f, 0.416608f},
    {0.316282f, 0.05349f, 0.425116f},  {0.347771f, 0.064616f, 0.430217f}, {0.379001f, 0.076253f, 0.432719f},
    {0.410113f, 0.087896f, 0.433098f}, {0.441207f, 0.099338f, 0.431594f}, {0.472328f, 0.110547f, 0.428334f},
    {0.503493f, 0.121575f, 0.423356f}, {0.534683f, 0.132534f, 0.416667f}, {0.565854f, 0.143567f, 0.408258f},
    {0.59694f, 0.154848f, 0.398125f},  {0.627847f, 0.166575f, 0.386276f}, {0.658463f, 0.178962f, 0.372748f},
    {0.688653f, 0.192239f, 0.357603f}, {0.718264f, 0.206636f, 0.340931f}, {0.747127f, 0.222378f, 0.322856f},
    {0.775059f, 0.239667f, 0.303526f}, {0.801871f, 0.258674f, 0.283099f}, {0.827372f, 0.279517f, 0.26175f},
    {0.851384f, 0.30226f, 0.239636f},  {0.873741f, 0.326906f, 0.216886f}, {0.894305f, 0.353399f, 0.193584f},
    {0.912966f, 0.381636f, 0.169755f}, {0.929644f, 0.411479f, 0.145367f}, {0.944285f, 0.442772f, 0.120354f},
    {0.956852f, 0.475356f, 0.094695f}, {0.967322f, 0.509078f, 0.068659f}, {0.975677f, 0.543798f, 0.043618f},
    {0.981895f, 0.579392f, 0.02625f},  {0.985952f, 0.61575f, 0.025592f},  {0.987819f, 0.652773f, 0.045581f},
    {0.987464f, 0.690366f, 0.07999f},  {0.984865f, 0.728427f, 0.120785f}, {0.980032f, 0.766837f, 0.166353f},
    {0.973088f, 0.805409f, 0.216877f}, {0.964394f, 0.843848f, 0.273391f}, {0.954997f, 0.881569f, 0.337475f},
    {0.947594f, 0.917399f, 0.410665f}, {0.947937f, 0.949318f, 0.491426f}, {0.961812f, 0.975924f, 0.571925f},
    {0.988362f, 0.998364f, 0.644924f},
};

template <size_t N> std::vector<float> evenlySpaced(const float (&colors)[N][3]) {
  std::vector<float> points;
  for (size_t i = 0; i < N; ++i)
    points.insert(points.end(), {float(i) / float(N - 1), colors[i][0], colors[i][1], colors[i][2]});
  return points;
}

struct Builtin {
  const char *name;
  const char *alias;
  ColorMap (*make)();
};

// Names, colours and colour spaces as in ParaView's ColorMaps.json. The matplotlib maps are "Diverging" there
// too; between close colours that is a smooth path in L*a*b*, within 1 / 255 of matplotlib's full table.
const Builtin kBuiltins[] = {
    {"Cool to Warm", "cool-to-warm",
     [] {
       // ParaView's default, with an opacity ramp so that it is usable for volumes as it stands.
       return ColorMap{"Cool to Warm",
                       {0.f, 0.23137254902f, 0.298039215686f, 0.752941176471f, 0.5f, 0.865f, 0.865f, 0.865f,
                        1.f, 0.705882352941f, 0.0156862745098f, 0.149019607843f},
                       {0.f, 0.f, 0.5f, 0.f, 1.f, 1.f, 0.5f, 0.f},
                       "Diverging",
                       {1.f, 1.f, 0.f}};
     }},
    {"Viridis (matplotlib)", "viridis",
     [] {
       return ColorMap{"Viridis (matplotlib)", evenlySpaced(kViridis), {}, "Diverging", {1.f, 0.f, 0.f}};
     }},
    {"Inferno (matplotlib)", "inferno",
     [] {
       return ColorMap{"Inferno (matplotlib)", evenlySpaced(kInferno), {}, "Diverging", {0.f, 1.f, 0.f}};
     }},
    {"Grayscale", "grayscale",
     [] {
       return ColorMap{"Grayscale", {0.f, 0.f, 0.f, 0.f, 1.f, 1.f, 1.f, 1.f}, {}, "RGB", {1.f, 0.f, 0.f}};
     }},
};

} // namespace

void checkColorMap(const ColorMap &map, const std::string &file, const std::string &position) {
  checkedColorSpace(map, file, position);
}

std::vector<std::string> builtinColorMapNames() {
  std::vector<std::string> names;
  for (const Builtin &builtin : kBuiltins)
    names.emplace_back(builtin.name);
  return names;
}

ColorMap builtinColorMap(const std::string &name) {
  const std::string key = lowercase(name);
  for (const Builtin &builtin : kBuiltins)
    if (key == lowercase(builtin.name) || key == builtin.alias)
      return builtin.make();
  std::string known;
  for (const Builtin &builtin : kBuiltins)
    known += std::string(known.empty() ? "" : ", ") + "\"" + builtin.name + "\" (" + builtin.alias + ")";
  throw Error("unknown built-in colour map \"" + name + "\"; known: " + known);
}

std::vector<Vec4f> sampleColorMap(const ColorMap &map, int count) {
  const ColorSpace space = checkedColorSpace(map, "", "colour map \"" + map.name + "\"");
  if (count <= 0)
    return {};
  // The samples span both sets of control points: opacity points outside the colour range (or the other way
  // round) still shape the table, and each function holds its end values beyond its own points.
  double low = map.rgbPoints.front(), high = map.rgbPoints[map.rgbPoints.size() - 4];
  if (!map.opacityPoints.empty()) {
    low = std::min(low, double(map.opacityPoints.front()));
    high = std::max(high, double(map.opacityPoints[map.opacityPoints.size() - 4]));
  }
  // Without opacity points, opacity ramps linearly from 0 to 1 over the colour range (constant 1 when that
  // range is a single value), the usual default of a volume renderer.
  const std::vector<float> opacity =
      !map.opacityPoints.empty() ? map.opacityPoints
      : low < high               ? std::vector<float>{float(low), 0.f, 0.5f, 0.f, float(high), 1.f, 0.5f, 0.f}
                                 : std::vector<float>{float(low), 1.f, 0.5f, 0.f};

  const auto unit = [](double v) { return static_cast<float>(std::clamp(v, 0.0, 1.0)); };
  std::vector<Vec4f> samples(count);
  for (int i = 0; i < count; ++i) {
    const double x = count > 1 ? low + (high - low) * i / (count - 1) : 0.5 * (low + high);
    const Triple rgb = colorAt(map.rgbPoints, space, x);
    samples[i] = {unit(rgb[0]), unit(rgb[1]), unit(rgb[2]), unit(opacityAt(opacity, x))};
  }
  return samples;
}

} // namespace uvr
