// The subcommands of `uvr`. Each registers itself on the app; its callback throws uvr::Error on failure.
#pragma once

#include <CLI/CLI.hpp>

namespace uvr {

void addRenderCommand(CLI::App &app);
void addInfoCommand(CLI::App &app);
void addCompareCommand(CLI::App &app);
void addConvertCommand(CLI::App &app);
void addViewCommand(CLI::App &app);
void addGenCommand(CLI::App &app);

} // namespace uvr
