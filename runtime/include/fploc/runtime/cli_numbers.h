// Mains built on CLI11: a number option given "nan" or "inf" is one error naming it. CLI11 reads both as
// numbers, and its Range/PositiveNumber checks let NaN through (fploc sim --noise nan wrote NaN ranges;
// fploc import-carmen --resolution nan wrote a map.yaml saying "resolution: nan").
#pragma once
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdlib>
#include <ostream>
#include <string>
#include <vector>

namespace fploc::rt {

// After CLI11_PARSE: false (and one line "PREFIX: --option VALUE: not a finite number" on err) when a given
// floating-point option's value, of the app or of a subcommand it ran, is not finite.
inline bool check_finite_options(const CLI::App& app, const std::string& prefix, std::ostream& err) {
  for (const CLI::Option* o : app.get_options())
    if (o->count() && o->get_type_name().find("FLOAT") != std::string::npos)
      for (const std::string& r : o->results())
        if (!std::isfinite(std::strtod(r.c_str(), nullptr))) {
          err << prefix << ": " << o->get_name() << " " << r << ": not a finite number\n";
          return false;
        }
  for (const CLI::App* sub : app.get_subcommands())
    if (!check_finite_options(*sub, prefix, err)) return false;
  return true;
}

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
