// Sample-count heat maps, as in the paper's figures: counts colour-coded with inferno, and a colour bar
// with its scale drawn into the image in a tiny built-in bitmap font.
#include <uvr/error.h>
#include <uvr/image.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

namespace uvr {

namespace {

// matplotlib's inferno at 17 evenly spaced points; linear interpolation between them stays within 7/255 of
// the full 256-entry table.
constexpr uint8_t kInferno[17][3] = {
    {0, 0, 4},      {11, 7, 36},    {33, 12, 74},   {61, 9, 101},    {87, 16, 110},  {113, 25, 110},
    {138, 34, 106}, {163, 44, 97},  {188, 55, 84},  {210, 70, 68},   {228, 90, 49},  {241, 115, 29},
    {249, 142, 9},  {252, 172, 17}, {249, 203, 53}, {242, 234, 105}, {252, 255, 164}};

/// inferno at t in [0, 1].
std::array<uint8_t, 3> inferno(double t) {
  const double x = std::clamp(t, 0.0, 1.0) * 16;
  const int i = std::min(int(x), 15);
  const double f = x - i;
  std::array<uint8_t, 3> rgb;
  for (int c = 0; c < 3; ++c)
    rgb[c] = uint8_t(std::lround(kInferno[i][c] * (1 - f) + kInferno[i + 1][c] * f));
  return rgb;
}

/// A 5x7 glyph, one string per row, '#' for a set pixel.
struct Glyph {
  char character;
  const char *rows[7];
};

constexpr int kGlyphWidth = 5, kGlyphHeight = 7, kAdvance = 6;

/// The colour bar's frame: mid grey, visible on the black of a background and of the map's low end.
constexpr std::array<uint8_t, 3> kFrame = {160, 160, 160};

constexpr Glyph kFont[] = {
    {'0', {" ### ", "#   #", "#  ##", "# # #", "##  #", "#   #", " ### "}},
    {'1', {"  #  ", " ##  ", "  #  ", "  #  ", "  #  ", "  #  ", " ### "}},
    {'2', {" ### ", "#   #", "    #", "   # ", "  #  ", " #   ", "#####"}},
    {'3', {"#####", "   # ", "  #  ", "   # ", "    #", "#   #", " ### "}},
    {'4', {"   # ", "  ## ", " # # ", "#  # ", "#####", "   # ", "   # "}},
    {'5', {"#####", "#    ", "#### ", "    #", "    #", "#   #", " ### "}},
    {'6', {"  ## ", " #   ", "#    ", "#### ", "#   #", "#   #", " ### "}},
    {'7', {"#####", "    #", "   # ", "  #  ", " #   ", " #   ", " #   "}},
    {'8', {" ### ", "#   #", "#   #", " ### ", "#   #", "#   #", " ### "}},
    {'9', {" ### ", "#   #", "#   #", " ####", "    #", "   # ", " ##  "}},
    {'a', {"     ", "     ", " ### ", "    #", " ####", "#   #", " ####"}},
    {'e', {"     ", "     ", " ### ", "#   #", "#####", "#    ", " ### "}},
    {'i', {"  #  ", "     ", " ##  ", "  #  ", "  #  ", "  #  ", " ### "}},
    {'l', {" ##  ", "  #  ", "  #  ", "  #  ", "  #  ", "  #  ", " ### "}},
    {'m', {"     ", "     ", "## # ", "# # #", "# # #", "#   #", "#   #"}},
    {'p', {"     ", "     ", "#### ", "#   #", "#### ", "#    ", "#    "}},
    {'r', {"     ", "     ", "# ## ", "##  #", "#    ", "#    ", "#    "}},
    {'s', {"     ", "     ", " ####", "#    ", " ### ", "    #", "#### "}},
    {'x', {"     ", "     ", "#   #", " # # ", "  #  ", " # # ", "#   #"}},
};

const Glyph *findGlyph(char c) {
  for (const Glyph &glyph : kFont)
    if (glyph.character == c)
      return &glyph;
  return nullptr;
}

/// Width in pixels of `text` drawn with font pixels of `unit` x `unit` image pixels.
int textWidth(const std::string &text, int unit) {
  return text.empty() ? 0 : (int(text.size()) * kAdvance - (kAdvance - kGlyphWidth)) * unit;
}

void fillRect(Image &image, int x0, int y0, int x1, int y1, std::array<uint8_t, 3> rgb) {
  for (int y = std::max(y0, 0); y < std::min(y1, image.height); ++y)
    for (int x = std::max(x0, 0); x < std::min(x1, image.width); ++x)
      std::copy(rgb.begin(), rgb.end(), image.pixel(x, y));
}

/// Fills a white rectangle with a black outline `outline` pixels wide, legible on any colour.
void fillOutlinedRect(Image &image, int x0, int y0, int x1, int y1, int outline) {
  fillRect(image, x0 - outline, y0 - outline, x1 + outline, y1 + outline, {0, 0, 0});
  fillRect(image, x0, y0, x1, y1, {255, 255, 255});
}

/// Draws `text` in white outlined in black, with its top left corner at (x, y).
void drawText(Image &image, int x, int y, const std::string &text, int unit) {
  const int outline = std::max(1, unit / 2);
  // All outlines first, so that no glyph's outline covers its neighbour's strokes.
  for (const std::array<uint8_t, 3> colour : {std::array<uint8_t, 3>{0, 0, 0}, {255, 255, 255}}) {
    const int grow = colour[0] == 0 ? outline : 0;
    for (size_t i = 0; i < text.size(); ++i) {
      const Glyph *glyph = findGlyph(text[i]);
      const int left = x + int(i) * kAdvance * unit;
      for (int row = 0; glyph && row < kGlyphHeight; ++row)
        for (int column = 0; column < kGlyphWidth; ++column)
          if (glyph->rows[row][column] == '#')
            fillRect(image, left + column * unit - grow, y + row * unit - grow,
                     left + (column + 1) * unit + grow, y + (row + 1) * unit + grow, colour);
    }
  }
}

/// Draws the colour bar for the scale [low, high] at the right edge: the title ("samples per pixel", or
/// "samples" where that does not fit), then the bar in a grey frame (its black end stays visible on black)
/// with ticks and labels at its minimum, middle and maximum. Leaves the image as it is when the bar would
/// cover too much of it; drops the title first.
void drawColorBar(Image &image, uint64_t low, uint64_t high) {
  // Font pixels grow with the image, so that the bar looks alike from 64 to 4096 pixels.
  const int unit = std::max(1, std::min(image.width, image.height) / 200);
  const int outline = std::max(1, unit / 2);
  const int glyphHeight = kGlyphHeight * unit, margin = 4 * unit;
  const int tickLength = 2 * unit, gap = unit + outline, barWidth = 6 * unit;
  const int barHeight = image.height / 2;

  // Counts are integers, so the middle tick marks the integer nearest the middle, where that lies.
  const uint64_t middle = low + (high - low) / 2;
  std::vector<uint64_t> values = {high, low};
  if (middle != low)
    values.push_back(middle);
  int labelWidth = 0;
  for (uint64_t value : values)
    labelWidth = std::max(labelWidth, textWidth(std::to_string(value), unit));
  const int scaleWidth = labelWidth + gap + tickLength + barWidth + 2 * outline;
  const int maxWidth = image.width * 3 / 5;
  std::string title = "samples per pixel";
  if (textWidth(title, unit) > maxWidth)
    title = "samples";
  const bool showTitle = std::max(scaleWidth, textWidth(title, unit)) <= maxWidth;
  const int titleHeight = showTitle ? glyphHeight + 3 * unit : 0;
  // Labels are centred on their ticks, so they reach half a glyph beyond the bar's ends; they need room to
  // stay apart, too.
  if (barHeight < 3 * glyphHeight || scaleWidth > maxWidth ||
      titleHeight + glyphHeight + barHeight > image.height - 2 * margin)
    return;

  const int right = image.width - margin - outline;
  if (showTitle)
    drawText(image, right - textWidth(title, unit), margin, title, unit);
  const int barTop = margin + titleHeight + glyphHeight / 2, barBottom = barTop + barHeight;
  const int barLeft = right - barWidth;
  fillRect(image, barLeft - outline, barTop - outline, right + outline, barBottom + outline, kFrame);
  for (int y = barTop; y < barBottom; ++y)
    fillRect(image, barLeft, y, right, y + 1, inferno(double(barBottom - 1 - y) / (barHeight - 1)));

  for (uint64_t value : values) {
    const double t = double(value - low) / double(high - low);
    const int tickTop = std::clamp(int(std::lround(barBottom - unit / 2.0 - t * (barHeight - unit))), barTop,
                                   barBottom - unit);
    fillOutlinedRect(image, barLeft - tickLength, tickTop, barLeft, tickTop + unit, outline);
    const std::string label = std::to_string(value);
    drawText(image, barLeft - tickLength - gap - textWidth(label, unit), tickTop + unit / 2 - glyphHeight / 2,
             label, unit);
  }
}

} // namespace

Image heatmapImage(const std::vector<uint32_t> &samplesPerPixel, int width, int height) {
  if (width <= 0 || height <= 0 || samplesPerPixel.size() != size_t(width) * size_t(height))
    throw Error("heat map: " + std::to_string(samplesPerPixel.size()) + " sample counts for a " +
                std::to_string(width) + "x" + std::to_string(height) + " image");
  const auto [lowest, highest] = std::minmax_element(samplesPerPixel.begin(), samplesPerPixel.end());
  const uint64_t low = *lowest;
  const uint64_t high = *highest > low ? *highest : low + 1; // a flat image still gets a scale

  Image image(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const uint32_t samples = samplesPerPixel[size_t(y) * size_t(width) + size_t(x)];
      const auto rgb = inferno(double(samples - low) / double(high - low));
      std::copy(rgb.begin(), rgb.end(), image.pixel(x, y));
    }
  drawColorBar(image, low, high);
  return image;
}

} // namespace uvr
