#include "commands.h"

#include <uvr/error.h>
#include <uvr/image.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <memory>

namespace uvr {

namespace {

struct CompareOptions {
  std::string first;
  std::string second;
  bool json = false;
};

void runCompare(const CompareOptions &o) {
  const Image a = readPng(o.first);
  const Image b = readPng(o.second);
  if (a.width != b.width || a.height != b.height)
    throw Error(o.second, "",
                "is " + std::to_string(b.width) + "x" + std::to_string(b.height) + " pixels, but " + o.first +
                    " is " + std::to_string(a.width) + "x" + std::to_string(a.height));
  const double similarity = ssim(a, b);
  const double peakSnr = psnr(a, b);

  if (o.json) {
    // Identical images have infinite PSNR, which JSON cannot hold: it is written as null.
    nlohmann::ordered_json result = {{"ssim", similarity}, {"psnr", nullptr}};
    if (std::isfinite(peakSnr))
      result["psnr"] = peakSnr;
    std::printf("%s\n", result.dump().c_str());
    return;
  }
  std::printf("SSIM %.6f\n", similarity);
  if (std::isinf(peakSnr))
    std::printf("PSNR inf dB\n");
  else
    std::printf("PSNR %.2f dB\n", peakSnr);
}

} // namespace

void addCompareCommand(CLI::App &app) {
  auto options = std::make_shared<CompareOptions>();
  CLI::App *cmd = app.add_subcommand(
      "compare", "Compare two PNGs: SSIM (as scikit-image computes it, Gaussian 11x11 window) and PSNR");
  cmd->add_option("A", options->first, "First PNG (e.g. the reference)")->required();
  cmd->add_option("B", options->second, "Second PNG, of the same size")->required();
  cmd->add_flag("--json", options->json,
                "Print {\"ssim\": ..., \"psnr\": ...}; psnr is null for identical images");
  cmd->callback([options] { runCompare(*options); });
}

} // namespace uvr
