#include "tf_editor.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

namespace uvr {

namespace {

ImU32 rgba(const Vec4f &c, float alpha = 1.f) {
  return ImGui::ColorConvertFloat4ToU32({c.x, c.y, c.z, alpha});
}

} // namespace

void makeOpacityPointsExplicit(ColorMap &map) {
  if (!map.opacityPoints.empty())
    return;
  const float low = map.rgbPoints.front(), high = map.rgbPoints[map.rgbPoints.size() - 4];
  map.opacityPoints = {low, 0.f, 0.5f, 0.f, high, 1.f, 0.5f, 0.f};
}

bool transferFunctionEditor(ColorMap &map, float width, float height) {
  makeOpacityPointsExplicit(map);
  std::vector<float> &points = map.opacityPoints;
  const float low = map.rgbPoints.front(), high = map.rgbPoints[map.rgbPoints.size() - 4];
  const float span = high > low ? high - low : 1.f;
  const ImVec2 origin = ImGui::GetCursorScreenPos();
  ImGui::InvisibleButton("transfer function", {width, height},
                         ImGuiButtonFlags_MouseButtonLeft | ImGuiButtonFlags_MouseButtonRight);
  ImDrawList *draw = ImGui::GetWindowDrawList();
  const auto toScreen = [&](float x, float a) {
    return ImVec2(origin.x + (x - low) / span * width, origin.y + (1.f - a) * height);
  };

  // The colours as a bar, dimmed where the function is transparent so that the curve reads as opacity.
  const int columns = std::max(2, int(width / 2.f));
  const std::vector<Vec4f> table = sampleColorMap(map, columns);
  for (int i = 0; i + 1 < columns; ++i) {
    const float x0 = origin.x + width * float(i) / float(columns - 1);
    const float x1 = origin.x + width * float(i + 1) / float(columns - 1);
    draw->AddRectFilledMultiColor({x0, origin.y}, {x1, origin.y + height}, rgba(table[i], 0.35f),
                                  rgba(table[i + 1], 0.35f), rgba(table[i + 1]), rgba(table[i]));
  }
  draw->AddRect(origin, {origin.x + width, origin.y + height}, IM_COL32(160, 160, 160, 255));

  std::vector<ImVec2> curve;
  for (size_t i = 0; i < points.size(); i += 4)
    curve.push_back(toScreen(points[i], points[i + 1]));
  draw->AddPolyline(curve.data(), int(curve.size()), IM_COL32(0, 0, 0, 255), ImDrawFlags_None, 4.f);
  draw->AddPolyline(curve.data(), int(curve.size()), IM_COL32(255, 255, 255, 255), ImDrawFlags_None, 2.f);

  static int dragged = -1;
  const ImVec2 mouse = ImGui::GetIO().MousePos;
  int hovered = -1;
  for (size_t i = 0; i < curve.size(); ++i) {
    const float dx = curve[i].x - mouse.x, dy = curve[i].y - mouse.y;
    if (dx * dx + dy * dy <= 49.f)
      hovered = int(i);
  }
  for (size_t i = 0; i < curve.size(); ++i) {
    const bool active = int(i) == dragged || int(i) == hovered;
    draw->AddCircleFilled(curve[i], active ? 6.f : 4.5f, IM_COL32(255, 255, 255, 255));
    draw->AddCircle(curve[i], active ? 6.f : 4.5f, IM_COL32(0, 0, 0, 255));
  }

  bool changed = false;
  const bool inside = ImGui::IsItemHovered();
  const float mouseX = std::clamp(low + (mouse.x - origin.x) / width * span, low, high);
  const float mouseA = std::clamp(1.f - (mouse.y - origin.y) / height, 0.f, 1.f);
  if (inside && ImGui::IsMouseClicked(ImGuiMouseButton_Left))
    dragged = hovered;
  if (!ImGui::IsMouseDown(ImGuiMouseButton_Left))
    dragged = -1;
  const size_t count = points.size() / 4;
  if (dragged >= 0 && size_t(dragged) < count) {
    const size_t i = size_t(dragged);
    // A point stays between its neighbours so that the points remain sorted.
    const float left = i > 0 ? points[4 * (i - 1)] : low;
    const float right = i + 1 < count ? points[4 * (i + 1)] : high;
    points[4 * i] = std::clamp(mouseX, left, right);
    points[4 * i + 1] = mouseA;
    changed = true;
  } else if (inside && hovered < 0 && ImGui::IsMouseDoubleClicked(ImGuiMouseButton_Left)) {
    size_t at = 0;
    while (at < count && points[4 * at] < mouseX)
      ++at;
    points.insert(points.begin() + ptrdiff_t(4 * at), {mouseX, mouseA, 0.5f, 0.f});
    changed = true;
  } else if (inside && hovered >= 0 && count > 2 && ImGui::IsMouseClicked(ImGuiMouseButton_Right)) {
    points.erase(points.begin() + ptrdiff_t(4 * hovered), points.begin() + ptrdiff_t(4 * hovered + 4));
    changed = true;
  }
  if (inside && hovered >= 0)
    ImGui::SetTooltip("x %.4g, opacity %.3f", double(points[4 * size_t(hovered)]),
                      double(points[4 * size_t(hovered) + 1]));
  return changed;
}

void colorLegend(ImDrawList *draw, const ColorMap &map, ValueRange range, const std::string &title,
                 ImVec2 corner, ImVec2 size) {
  draw->AddRectFilled(corner, {corner.x + size.x, corner.y + size.y}, IM_COL32(32, 32, 36, 255));
  const float lineHeight = ImGui::GetTextLineHeight();
  draw->AddText({corner.x + 8.f, corner.y + 8.f}, IM_COL32(235, 235, 235, 255), title.c_str());
  const float barTop = corner.y + 16.f + 1.5f * lineHeight, barBottom = corner.y + size.y - 16.f - lineHeight;
  const float barLeft = corner.x + 10.f, barRight = barLeft + 22.f;
  const int rows = std::max(2, int(barBottom - barTop));
  const std::vector<Vec4f> table = sampleColorMap(map, rows);
  for (int i = 0; i + 1 < rows; ++i) {
    // Top is the range's maximum.
    const float y0 = barBottom - (barBottom - barTop) * float(i + 1) / float(rows - 1);
    const float y1 = barBottom - (barBottom - barTop) * float(i) / float(rows - 1);
    draw->AddRectFilledMultiColor({barLeft, y0}, {barRight, y1}, rgba(table[i + 1]), rgba(table[i + 1]),
                                  rgba(table[i]), rgba(table[i]));
  }
  draw->AddRect({barLeft, barTop}, {barRight, barBottom}, IM_COL32(200, 200, 200, 255));
  constexpr int kTicks = 5;
  for (int t = 0; t < kTicks; ++t) {
    const float f = float(t) / float(kTicks - 1);
    const float y = barBottom - f * (barBottom - barTop);
    char label[32];
    std::snprintf(label, sizeof label, "%.4g", double(range.min + f * (range.max - range.min)));
    draw->AddLine({barRight, y}, {barRight + 5.f, y}, IM_COL32(200, 200, 200, 255));
    draw->AddText({barRight + 8.f, y - 0.5f * lineHeight}, IM_COL32(235, 235, 235, 255), label);
  }
}

} // namespace uvr
