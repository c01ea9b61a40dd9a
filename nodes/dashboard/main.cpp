// fploc-dashboard's main: the runtime's node_main plus the flags DESIGN.md promises,
// `--bind ADDR` and `--port N` (and `--web-root DIR`), translated to `--set bind=ADDR` etc. so that
// they override the graph's options like any other --set.
#include <string>
#include <vector>

#include "fploc/runtime/node.h"

int main(int argc, char** argv) {
  std::vector<std::string> args{argv[0]};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto flag = [&](const std::string& name, const char* field) {
      if (a == name && i + 1 < argc) {
        args.push_back("--set");
        args.push_back(std::string(field) + "=" + argv[++i]);
        return true;
      }
      if (a.rfind(name + "=", 0) == 0) {
        args.push_back("--set");
        args.push_back(std::string(field) + "=" + a.substr(name.size() + 1));
        return true;
      }
      return false;
    };
    if (flag("--bind", "bind") || flag("--port", "port") || flag("--web-root", "web_root")) continue;
    args.push_back(a);
  }
  std::vector<char*> out;
  for (auto& s : args) out.push_back(s.data());
  out.push_back(nullptr);
  return fploc::rt::node_main(int(args.size()), out.data());
}
