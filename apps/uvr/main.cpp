// uvr: renders unstructured volumes with empty-space skipping and adaptive sampling.
#include "commands.h"

#include <uvr/error.h>
#include <uvr/system.h>

#include <cstdio>
#include <new>

int main(int argc, char **argv) {
  CLI::App app{"uvr: fast volume rendering of unstructured meshes (tetrahedra, hexahedra, wedges, pyramids)"};
  app.require_subcommand(1);
  uvr::addRenderCommand(app);
  uvr::addInfoCommand(app);
  uvr::addCompareCommand(app);
  uvr::addConvertCommand(app);
  uvr::addViewCommand(app);
  uvr::addGenCommand(app);
  // Every command reads input that may claim far more memory than it holds (docs/cli.md, "Memory limit").
  for (CLI::App *command : app.get_subcommands({}))
    command->add_option_function<std::string>(
        "--memory-limit", [](const std::string &text) { uvr::setMemoryLimit(uvr::parseByteSize(text)); },
        "Most memory that input may claim: bytes, or with K, M, G, T (default 4G, or $UVR_MEMORY_LIMIT)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError &e) {
    // --help and --version succeed as CLI11 has them; every other command-line error is an input error.
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success))
      return app.exit(e);
    std::fprintf(stderr, "uvr: error: %s (uvr COMMAND --help lists the options)\n", e.what());
    return 2;
  } catch (const uvr::Error &e) {
    std::fprintf(stderr, "uvr: error: %s\n", e.what());
    return 2;
  } catch (const std::bad_alloc &) {
    std::fprintf(stderr, "uvr: error: out of memory\n");
    return 2;
  } catch (const std::exception &e) {
    std::fprintf(stderr, "uvr: error: %s\n", e.what());
    return 1;
  }
  return 0;
}
