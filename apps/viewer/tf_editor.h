// The viewer's transfer-function widgets, drawn with Dear ImGui.
#pragma once

#include <uvr/color_map.h>
#include <uvr/mesh.h>

#include <imgui.h>

#include <string>

namespace uvr {

/// The preset's colours as a bar with its opacity curve over it. Drag a point to move it, double-click to
/// add one, right-click a point to remove it. Returns true when the opacity points changed.
bool transferFunctionEditor(ColorMap &map, float width, float height);

/// A vertical colour bar for `map` over `range`, labelled with `title` and five values, filling the rectangle
/// [corner, corner + size] of `drawList`.
void colorLegend(ImDrawList *drawList, const ColorMap &map, ValueRange range, const std::string &title,
                 ImVec2 corner, ImVec2 size);

/// Opacity points the editor can move: the preset's own, or its implicit ramp 0 -> 1 over the colours.
void makeOpacityPointsExplicit(ColorMap &map);

} // namespace uvr
