#!/usr/bin/env python3
"""The layering, checked on the sources (includes and CMake), so that an arrow the wrong way fails a test:

  1. nothing under modules/ includes a header of nodes/ or tools/ (or an LCM message header: modules are
     transport-free), nor names a nodes/ or tools/ path in its CMakeLists.txt;
  2. adapters/ and config/ include nothing from nodes/ or tools/, and config/ no LCM message;
  3. no node links a library defined in another node's folder, nor includes a header from one.

Usage: check_structure.py ROOT. Prints every violation (file:line: what) and exits 1 when there is any.
"""
import os
import re
import sys

ROOT = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", ".."))
SRC_EXT = (".h", ".hpp", ".cpp", ".cc")
INCLUDE_RE = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]')
LCM_RE = re.compile(r"^fploc/\w+_t\.hpp$|^lcm/")


def files(top, exts):
    for d, dirs, fs in os.walk(os.path.join(ROOT, top)):
        dirs[:] = [x for x in dirs if x not in ("build", "node_modules", "__pycache__")]
        for f in fs:
            if f.endswith(exts) or (exts == "cmake" and f == "CMakeLists.txt"):
                yield os.path.join(d, f)


def rel(p):
    return os.path.relpath(p, ROOT)


def headers_under(top):
    """Include names a header under `top` can be reached by: its path below an include/ folder, its path
    relative to its own folder, and its path relative to the top folder."""
    names = {}
    for p in files(top, (".h", ".hpp")):
        r = rel(p)
        parts = r.split(os.sep)
        if "include" in parts:
            names["/".join(parts[parts.index("include") + 1:])] = r
        names[os.path.basename(p)] = r
    return names


def includes(path):
    with open(path, errors="replace") as f:
        for n, line in enumerate(f, 1):
            m = INCLUDE_RE.match(line)
            if m:
                yield n, m.group(1)


def resolves_into(path, inc, top):
    """True when the quoted include `inc` of `path` is a file under ROOT/top (relative includes)."""
    cand = os.path.normpath(os.path.join(os.path.dirname(path), inc))
    return os.path.exists(cand) and rel(cand).split(os.sep)[0] == top


def main():
    bad = []
    upper = {}
    for top in ("nodes", "tools"):
        for name, where in headers_under(top).items():
            upper.setdefault(name, where)
    # 1 + 2: modules, adapters, config
    for layer in ("modules", "adapters", "config"):
        for p in files(layer, SRC_EXT):
            for n, inc in includes(p):
                where = None
                if inc.startswith("fploc/nodes/") or inc.startswith("fploc/tools/"):
                    where = inc
                elif any(resolves_into(p, inc, t) for t in ("nodes", "tools")):
                    where = inc
                elif "/" in inc and inc in upper:
                    where = upper[inc]
                if where:
                    bad.append(f"{rel(p)}:{n}: {layer}/ includes {where} (from nodes/ or tools/)")
                if layer in ("modules", "config") and LCM_RE.match(inc):
                    bad.append(f"{rel(p)}:{n}: {layer}/ includes the LCM header {inc} (no transport here)")
        for p in files(layer, "cmake"):
            with open(p) as f:
                for n, line in enumerate(f, 1):
                    code = line.split("#", 1)[0]
                    if re.search(r"(PROJECT_SOURCE_DIR|CMAKE_SOURCE_DIR)\}/(nodes|tools)/|\.\./(nodes|tools)/", code):
                        bad.append(f"{rel(p)}:{n}: {layer}/ CMake names a nodes/ or tools/ path")
    # 3: nodes
    node_dirs = sorted(d for d in os.listdir(os.path.join(ROOT, "nodes")) if os.path.isdir(os.path.join(ROOT, "nodes", d)))
    defined = {}  # target -> node folder
    for d in node_dirs:
        cm = os.path.join(ROOT, "nodes", d, "CMakeLists.txt")
        if not os.path.exists(cm):
            continue
        text = open(cm).read()
        for m in re.finditer(r"fploc_add_library\(\s*([\w-]+)", text):
            defined["fploc_" + m.group(1)] = d
        for m in re.finditer(r"fploc_add_node\(\s*([\w-]+)", text):
            defined["fploc_node_" + m.group(1)] = d
            defined["fploc-" + m.group(1)] = d
        for m in re.finditer(r"\badd_library\(\s*([\w-]+)", text):
            defined[m.group(1)] = d
    for d in node_dirs:
        cm = os.path.join(ROOT, "nodes", d, "CMakeLists.txt")
        if os.path.exists(cm):
            with open(cm) as f:
                for n, line in enumerate(f, 1):
                    code = line.split("#", 1)[0]
                    for tok in re.findall(r"[\w-]+", code):
                        owner = defined.get(tok)
                        if owner and owner != d and not re.search(r"(add_library|fploc_add_library|fploc_add_node)\(\s*" + re.escape(tok), code):
                            bad.append(f"nodes/{d}/CMakeLists.txt:{n}: node {d} links {tok}, a library of node {owner}")
                    if re.search(r"\$\{(PROJECT_SOURCE_DIR|CMAKE_SOURCE_DIR)\}/nodes/(?!" + re.escape(d) + r"\b)", code):
                        bad.append(f"nodes/{d}/CMakeLists.txt:{n}: names another node's folder")
        for p in files(os.path.join("nodes", d), SRC_EXT):
            for n, inc in includes(p):
                cand = os.path.normpath(os.path.join(os.path.dirname(p), inc))
                parts = rel(cand).split(os.sep)
                if os.path.exists(cand) and parts[0] == "nodes" and parts[1] != d:
                    bad.append(f"{rel(p)}:{n}: includes {rel(cand)} of node {parts[1]}")
                if inc.startswith("fploc/nodes/"):
                    owner = upper.get(inc, "?")
                    if not owner.startswith(os.path.join("nodes", d) + os.sep):
                        bad.append(f"{rel(p)}:{n}: includes {inc} ({owner}), another node's header")
    for b in bad:
        print(b)
    print(f"structure: {len(bad)} violation(s); checked modules/, adapters/, config/ includes and CMake, "
          f"{len(node_dirs)} node folders")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
