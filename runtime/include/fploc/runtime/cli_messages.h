// Mains built on CLI11: a parse error (a typo'd option, a stray argument) as one line naming the command.
#pragma once
#include <CLI/CLI.hpp>

#include <string>
#include <vector>

namespace fploc::rt {

// A parse error of a CLI11 main as one line naming the command: a typo'd option was "The following arguments were not
// expected: Walls --layer" (the arguments reversed, no command named) and a second line "Run with --help ...".
// Now "fploc map: unknown option '--layer' (fploc map --help lists the options)", "PROG: unexpected argument 'x' ...",
// and CLI11's own text for the others ("PROG: --plan: 1 required TEXT missing (...)"). The exit codes stay CLI11's.
inline std::string cli_error_text(const CLI::App& app, const CLI::Error& e, const std::string& prog) {
  const std::string help = " (" + prog + " --help lists the options)";
  if (dynamic_cast<const CLI::ExtrasError*>(&e)) {
    const std::vector<std::string> rest = app.remaining(true);
    for (const auto& r : rest)
      if (r.size() > 1 && r[0] == '-') return prog + ": unknown option '" + r + "'" + help;
    if (!rest.empty()) return prog + ": unexpected argument '" + rest.front() + "'" + help;
  }
  return prog + ": " + e.what() + help;
}

// Installs cli_error_text as the app's failure message (CLI11_PARSE prints it on stderr).
inline void install_cli_messages(CLI::App& app, const std::string& prog) {
  app.failure_message([prog](const CLI::App* a, const CLI::Error& e) { return cli_error_text(*a, e, prog) + "\n"; });
}

}  // namespace fploc::rt
