// Scripts for the viewer: camera moves and transfer-function edits replayed one per frame, and screenshots,
// so that the viewer runs without a person (tests, documentation images).
//
// One command per line; '#' starts a comment; angles in degrees:
//   orbit AZIMUTH ELEVATION   turn the eye about the focal point (as a left-button drag)
//   pan DX DY                 move across the view by DX, DY view heights (as a right-button drag)
//   zoom FACTOR               divide the distance to the focal point by FACTOR (as the wheel)
//   reset-camera              back to the starting camera
//   mode NAME                 reference | skip | adaptive | full
//   s1 X | s2 X | p X         sampling settings (0: the default)
//   preset NAME               a built-in preset or one of the --tf file's
//   range LO HI               scalar range of the transfer function
//   opacity V A [V A ...]     replace the opacity points: opacity A in [0, 1] at field value V (after range)
//   heatmap on|off            show samples per pixel instead of the image
//   screenshot NAME           wait for the full-resolution frame, then write PREFIX-NAME.png (the window),
//                             PREFIX-NAME-frame.png (the rendered frame) and PREFIX-NAME.json (the view)
// The viewer closes after the last line.
#pragma once

#include <string>
#include <vector>

namespace uvr {

struct ScriptCommand {
  std::string name;
  std::vector<std::string> words; ///< the arguments, as written
  std::vector<float> numbers;     ///< the arguments, when all are numbers
  int line = 0;
};

/// Reads and checks a script; throws uvr::Error naming the file and line.
std::vector<ScriptCommand> readViewScript(const std::string &path);

} // namespace uvr
