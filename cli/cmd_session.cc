// svbtdf session verify: checks a capture session against its plan and journal.

#include <cstdio>
#include <memory>
#include <string>

#include "commands.h"
#include "svbtdf/common/error.h"
#include "svbtdf/session/session.h"

namespace svbtdf::cli {
namespace {

// Exit code of `session verify` for a session that is readable but incomplete or damaged.
constexpr int kIncompleteExitCode = 3;

struct VerifyOptions {
  std::string session;
  bool skip_crc = false;
  bool decode = false;
};

}  // namespace

void AddSessionCommand(CLI::App& app) {
  CLI::App* session = app.add_subcommand("session", "Inspect capture sessions");
  session->require_subcommand(1);
  auto options = std::make_shared<VerifyOptions>();
  CLI::App* verify = session->add_subcommand(
      "verify", "Check a session against its plan and journal: exit 0 only when complete and intact");
  verify->add_option("session", options->session, "session folder")->required();
  verify->add_flag("--no-crc", options->skip_crc, "check sizes only (fast), not the CRC-32 of every image");
  verify->add_flag("--decode", options->decode,
                   "also decode every image (slow): finds images journalled with their damage");
  verify->callback([options] {
    const session::Session session = session::Session::Open(options->session);
    const session::SessionVerification report = session.Verify(!options->skip_crc, options->decode);
    std::printf("%s: %zu of %zu planned images journalled; %s\n", options->session.c_str(), session.entries().size(),
                session.planned_keys().size(), report.Summary().c_str());
    const auto list = [](const char* what, const std::vector<std::string>& keys) {
      for (const std::string& key : keys) std::printf("  %s %s\n", what, key.c_str());
    };
    list("missing", report.missing);
    list("corrupt", report.corrupt);
    list("duplicated", report.duplicated);
    list("unexpected", report.unexpected);
    if (!report.complete()) {
      std::fflush(stdout);
      throw CLI::RuntimeError(kIncompleteExitCode);
    }
  });
}

}  // namespace svbtdf::cli
