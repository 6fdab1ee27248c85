// svbtdf: capture, calibrate and fit spatially varying BTDFs of thin transparent slabs.
// This file only wires the subcommands together and maps every error to one line on stderr
// and an exit code (2: bad input or usage, 1: I/O, hardware or numerical failure,
// 3: an incomplete session (acquire, session verify), 4: --strict and the output drew quality
// warnings (docs/quality.md; the output is still written),
// 130: interrupted; the work done so far is kept and the command can be re-run to resume).

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <exception>
#include <new>
#include <string>

#include "commands.h"
#include "svbtdf/common/error.h"
#include "svbtdf/common/interrupt.h"
#include "svbtdf/common/progress.h"

namespace {

constexpr int kUsageExitCode = 2;

std::string SelectedCommandPath(const CLI::App& app) {
  std::string path;
  const CLI::App* current = &app;
  while (!current->get_subcommands().empty()) {
    current = current->get_subcommands().front();
    path += current->get_name() + " ";
  }
  return path;
}

}  // namespace

int main(int argc, char** argv) {
  // First of all: a Ctrl-C during start-up must stop cleanly too, not kill the process with the
  // signal (issue 15).
  svbtdf::common::InstallInterruptHandler();
  CLI::App app{"svbtdf: measure and fit the BTDF of thin transparent slabs (dual-microfacet model)",
               "svbtdf"};
  app.set_version_flag("--version", std::string("svbtdf ") + SVBTDF_VERSION);
  app.require_subcommand(1);
  bool quiet = false;
  bool verbose = false;
  app.add_flag("-q,--quiet", quiet, "no progress bars; warnings and errors only");
  app.add_flag("-v,--verbose", verbose, "debug logging");
  app.parse_complete_callback([&] {
    spdlog::set_pattern("%^[%l]%$ %v");
    spdlog::set_level(quiet ? spdlog::level::warn
                            : (verbose ? spdlog::level::debug : spdlog::level::info));
    svbtdf::common::ProgressBar::SetEnabled(!quiet);
  });

  svbtdf::cli::AddAllCommands(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {
    return app.exit(e);  // --help, --version
  } catch (const CLI::RuntimeError& e) {
    return e.get_exit_code();  // a command that reported its own outcome (e.g. an incomplete session)
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "svbtdf: error: %s (see 'svbtdf %s--help')\n", e.what(),
                 SelectedCommandPath(app).c_str());
    return kUsageExitCode;
  } catch (const svbtdf::common::Error& e) {
    std::fprintf(stderr, "svbtdf: error: %s\n", e.what());
    return svbtdf::common::ExitCodeFor(e.kind());
  } catch (const std::filesystem::filesystem_error& e) {
    // A folder the system refuses (a symbolic link loop, no permission, a file where a folder
    // should be) is the user's to fix, not a bug: name the path and the system's reason.
    std::fprintf(stderr, "svbtdf: error: %s: %s\n", e.path1().c_str(), e.code().message().c_str());
    return 1;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "svbtdf: error: out of memory (try a smaller --threads or tile size)\n");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "svbtdf: internal error: %s (please report this with the command line)\n",
                 e.what());
    return 1;
  }
  return 0;
}
