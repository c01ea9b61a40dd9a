// Mains built on CLI11: a number option given "nan" or "inf" is one error naming it. CLI11 reads both as
// numbers, and its Range/PositiveNumber checks let NaN through (fploc sim --noise nan wrote NaN ranges;
// fploc import-carmen --resolution nan wrote a map.yaml saying "resolution: nan").
#pragma once
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdlib>
#include <ostream>
#include <string>

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

}  // namespace fploc::rt
