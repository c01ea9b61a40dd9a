// Names in what the tools print. File names, topic, channel and layer names come from files and the command line
// and may hold any bytes: control characters (a terminal escape), bytes that are not UTF-8 (a Latin-1 file name, a
// damaged recording). Text output escapes them; JSON output replaces them, so both stay one clean document.
#pragma once
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <string_view>

namespace fploc {

// s for a terminal: every byte of a control character (C0, DEL, the C1 controls U+0080..U+009F), every byte that
// is not part of valid UTF-8, and the backslash as \xHH (lower-case hex); valid UTF-8 otherwise as it is.
// printable("/imu\x1b[2J\xe9") == "/imu\\x1b[2J\\xe9".
std::string printable(std::string_view s);

// j as JSON text, like j.dump(indent) (-1: compact, one line). A string holding bytes that are not UTF-8 gets U+FFFD
// for each bad byte: nlohmann's dump() throws type_error 316 on them (the tool aborted, exit 134, or printed an
// error instead of its output). Every tool and node that prints or writes JSON uses this.
std::string json_text(const nlohmann::json& j, int indent = -1);

// s as XML character data or an attribute value (SVG text and titles): &, <, > and " as entities.
std::string xml_text(std::string_view s);

}  // namespace fploc
