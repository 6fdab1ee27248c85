#!/usr/bin/env python3
"""Checks that the include dependencies between svbtdf's library folders go one way.

The layering is written down once, in docs/architecture.md, inside a fenced block whose info
string is ``layers``; one line per folder, ``folder: dep, dep, ...`` (the folders it may include
besides itself; nothing after the colon means "only itself"; ``*`` means "every library"):

    ```layers
    common:
    model: common
    cli: *
    ```

A folder whose right-hand side is ``*`` (cli, tests, bench) is a consumer, not a library. Every
other folder is a library with the shape ``<folder>/include/svbtdf/<folder>/`` + ``<folder>/src/``.

What is checked (each finding is printed as ``path:line: message``, paths relative to the root):

* every ``#include "svbtdf/<m>/..."`` (or ``<...>``) in a ``*.h``/``*.cc`` under
  ``<folder>/include/`` and ``<folder>/src/`` of a library folder: <m> must be the folder itself
  or one it may include;
* every such include anywhere in a consumer folder: <m> must be a library of the table;
* a file under ``<folder>/include/`` must live in ``<folder>/include/svbtdf/<folder>/``
  (a header filed in another folder's namespace is an error);
* every ``namespace svbtdf...`` a library folder's sources open is ``svbtdf::<folder>`` (or nested
  in it), or ``svbtdf::<m>`` of a folder <m> it may include (to forward-declare one of its types);
  the bare ``svbtdf`` namespace belongs to no folder and is refused;
* each library folder's CMakeLists.txt: the ``svbtdf::<m>`` entries of ``PUBLIC_DEPS`` and
  ``PRIVATE_DEPS`` in ``svbtdf_add_library(...)`` (and of ``target_link_libraries(svbtdf_<folder>
  ...)``) respect the same table, and the library's NAME is the folder's name;
* a folder on disk that has ``include/svbtdf/`` but is missing from the table is an error;
  a folder of the table that is absent on disk is skipped silently (moves happen in steps);
* the table itself: known folders only, no folder listed twice, no cycle;
* if docs/architecture.md has a ```mermaid block, its edges (``a --> b``: a may include b) must
  say the same as the table: the transitive closure of the picture equals the table.

Exit status 0 and a one-line summary when clean, 1 when anything is found, 2 on a usage error.

    python3 scripts/check_layers.py              check the tree this script lives in
    python3 scripts/check_layers.py --root DIR   check another tree
    python3 scripts/check_layers.py --self-test  build fake trees in a temporary folder and
                                                 assert that the check finds exactly what it should
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile

ARCHITECTURE_DOC = os.path.join("docs", "architecture.md")
SOURCE_SUFFIXES = (".h", ".cc")
INCLUDE_RE = re.compile(r'^\s*#\s*include\s*[<"](svbtdf/([A-Za-z0-9_]+)/[^">]*)[">]')
# A folder whose name is a C++ keyword declares its names in another namespace (docs/architecture.md).
NAMESPACE_FOLDERS = {"exporter": "export"}
NAMESPACE_RE = re.compile(r'^\s*namespace\s+svbtdf((?:::[A-Za-z0-9_]+)*)\s*\{')
FENCE_RE = re.compile(r"^\s*```\s*([A-Za-z0-9_-]*)\s*$")
MERMAID_EDGE_RE = re.compile(
    r"([A-Za-z0-9_]+)(?:\s*[\[\(\{][^\]\)\}]*[\]\)\}])?\s*-->\s*(?:\|[^|]*\|\s*)?([A-Za-z0-9_]+)")
EVERYTHING = "*"


class Finding:
    """One violation, printed as ``path:line: message``."""

    def __init__(self, path, line, message):
        self.path, self.line, self.message = path, line, message

    def __str__(self):
        return f"{self.path}:{self.line}: {self.message}"


def read_fenced_blocks(text, info):
    """Yields (first_line_number, [lines]) of every ```<info> block of a markdown text."""
    lines = text.splitlines()
    i = 0
    while i < len(lines):
        m = FENCE_RE.match(lines[i])
        if m and m.group(1) == info:
            start, body = i + 2, []
            i += 1
            while i < len(lines) and not FENCE_RE.match(lines[i]):
                body.append(lines[i])
                i += 1
            yield start, body
        i += 1


def parse_layers(doc_path, doc_rel, findings):
    """Reads the ```layers block: returns an ordered dict folder -> set of deps, or '*'."""
    with open(doc_path, encoding="utf-8") as f:
        text = f.read()
    blocks = list(read_fenced_blocks(text, "layers"))
    if len(blocks) != 1:
        findings.append(Finding(doc_rel, 1, f"expected exactly one ```layers block, found {len(blocks)}"))
        return {}, text
    start, body = blocks[0]
    table, where = {}, {}
    for offset, raw in enumerate(body):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        number = start + offset
        if ":" not in line:
            findings.append(Finding(doc_rel, number, f"layers line is not 'folder: deps': {raw.strip()!r}"))
            continue
        folder, deps = (part.strip() for part in line.split(":", 1))
        if folder in table:
            findings.append(Finding(doc_rel, number, f"{folder} is listed twice in the layers block"))
            continue
        where[folder] = number
        if deps == EVERYTHING:
            table[folder] = EVERYTHING
        else:
            table[folder] = {d.strip() for d in deps.replace(",", " ").split() if d.strip()}
    libraries = [f for f, deps in table.items() if deps != EVERYTHING]
    for folder, deps in table.items():
        if deps == EVERYTHING:
            continue
        for dep in sorted(deps):
            if dep not in libraries:
                findings.append(Finding(doc_rel, where[folder],
                                        f"{folder} may include {dep}, which is no library of the table"))
        deps.discard(folder)
    cycle = find_cycle({f: table[f] for f in libraries})
    if cycle:
        findings.append(Finding(doc_rel, where[cycle[0]], "the layers have a cycle: " + " -> ".join(cycle)))
    return table, text


def find_cycle(graph):
    """Returns one cycle [a, b, ..., a] of a dict node -> set(nodes), or None."""
    state = {}

    def visit(node, path):
        state[node] = "open"
        for nxt in sorted(graph.get(node, ())):
            if nxt not in graph:
                continue
            if state.get(nxt) == "open":
                return path[path.index(nxt):] + [nxt]
            if nxt not in state:
                found = visit(nxt, path + [nxt])
                if found:
                    return found
        state[node] = "done"
        return None

    for node in graph:
        if node not in state:
            found = visit(node, [node])
            if found:
                return found
    return None


def closure(graph, node):
    """Everything reachable from node (node excluded unless on a cycle)."""
    seen, todo = set(), list(graph.get(node, ()))
    while todo:
        n = todo.pop()
        if n not in seen:
            seen.add(n)
            todo.extend(graph.get(n, ()))
    return seen


def check_mermaid(text, doc_rel, table, findings):
    """The picture must say what the table says (compared as transitive closures)."""
    libraries = {f for f, deps in table.items() if deps != EVERYTHING}
    for start, body in read_fenced_blocks(text, "mermaid"):
        edges, nodes = {}, set()
        for offset, raw in enumerate(body):
            for a, b in MERMAID_EDGE_RE.findall(raw):
                for n in (a, b):
                    if n not in table:
                        findings.append(Finding(doc_rel, start + offset,
                                                f"the mermaid picture names {n}, which the layers block does not"))
                nodes.update((a, b))
                edges.setdefault(a, set()).add(b)
        for folder in sorted(table):
            deps = table[folder]
            if deps == EVERYTHING:
                if folder in nodes and closure(edges, folder) & libraries != libraries:
                    missing = sorted(libraries - closure(edges, folder))
                    findings.append(Finding(doc_rel, start, f"the mermaid picture does not connect {folder} "
                                            f"to every library (missing: {', '.join(missing)})"))
                continue
            if folder not in nodes:
                findings.append(Finding(doc_rel, start, f"the mermaid picture has no {folder}"))
                continue
            drawn = closure(edges, folder) - {folder}
            if drawn != deps:
                extra, missing = sorted(drawn - deps), sorted(deps - drawn)
                detail = "; ".join(p for p in (
                    f"draws {', '.join(extra)} not in the table" if extra else "",
                    f"lacks {', '.join(missing)}" if missing else "") if p)
                findings.append(Finding(doc_rel, start, f"the mermaid picture disagrees with the layers "
                                        f"block for {folder}: {detail}"))


def source_files(top):
    """Every *.h / *.cc under top, sorted, as absolute paths."""
    out = []
    for dirpath, dirnames, filenames in os.walk(top):
        dirnames.sort()
        for name in sorted(filenames):
            if name.endswith(SOURCE_SUFFIXES):
                out.append(os.path.join(dirpath, name))
    return out


def allowed_text(folder, deps):
    return ", ".join([f"{folder} itself"] + sorted(deps)) if deps else f"{folder} itself only"


def check_includes(root, path, folder, deps, libraries, findings, stats):
    rel = os.path.relpath(path, root)
    stats["files"] += 1
    with open(path, encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            m = INCLUDE_RE.match(line)
            if not m:
                continue
            stats["includes"] += 1
            target, module = m.group(1), m.group(2)
            if module not in libraries:
                findings.append(Finding(rel, number, f"svbtdf/{module}/ is no library folder of {ARCHITECTURE_DOC} "
                                        f"(included as {target})"))
            elif deps != EVERYTHING and module != folder and module not in deps:
                findings.append(Finding(rel, number, f"{folder} may not include {target} "
                                        f"(allowed: {allowed_text(folder, deps)})"))


def check_namespaces(root, path, folder, deps, findings):
    """A library folder declares its names in svbtdf::<folder>, reopening another room's namespace
    only to forward-declare a type of a folder it may include."""
    rel = os.path.relpath(path, root)
    with open(path, encoding="utf-8", errors="replace") as f:
        for number, line in enumerate(f, 1):
            m = NAMESPACE_RE.match(line)
            if not m:
                continue
            room = m.group(1)[2:].split("::")[0] if m.group(1) else ""
            room = NAMESPACE_FOLDERS.get(room, room)
            if not room:
                findings.append(Finding(rel, number, f"namespace svbtdf is no room's; {folder}/ declares its "
                                        f"names in svbtdf::{folder}"))
            elif room != folder and room not in deps:
                findings.append(Finding(rel, number, f"{folder}/ opens namespace svbtdf::{room}, a room it may "
                                        f"not include (allowed: {allowed_text(folder, deps)})"))


def check_header_places(root, folder, findings):
    include_dir = os.path.join(root, folder, "include")
    if not os.path.isdir(include_dir):
        return
    for path in source_files(include_dir):
        parts = os.path.relpath(path, include_dir).split(os.sep)
        rel = os.path.relpath(path, root)
        if len(parts) >= 3 and parts[0] == "svbtdf":
            if parts[1] != folder:
                findings.append(Finding(rel, 1, f"svbtdf/{parts[1]}/ headers belong in {parts[1]}/include, "
                                        f"not {folder}/include"))
        else:
            findings.append(Finding(rel, 1, f"headers of {folder} belong in {folder}/include/svbtdf/{folder}/"))


def cmake_tokens(text):
    """Yields (token, line_number) of a CMake file: comments stripped, parentheses as tokens."""
    for number, line in enumerate(text.splitlines(), 1):
        line = re.sub(r'"[^"]*"', lambda m: m.group(0).replace("#", " "), line)
        line = line.split("#", 1)[0]
        for token in re.findall(r'\(|\)|"[^"]*"|[^\s()"]+', line):
            yield token, number


def cmake_calls(text):
    """Yields (command, [(arg, line)...]) for every command call of a CMake file."""
    tokens = list(cmake_tokens(text))
    i = 0
    while i < len(tokens):
        token, _ = tokens[i]
        if i + 1 < len(tokens) and tokens[i + 1][0] == "(" and re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*", token):
            depth, args, j = 1, [], i + 2
            while j < len(tokens) and depth:
                t = tokens[j]
                if t[0] == "(":
                    depth += 1
                elif t[0] == ")":
                    depth -= 1
                if depth:
                    args.append(t)
                j += 1
            yield token.lower(), args
            i = j
        else:
            i += 1


ADD_LIBRARY_KEYWORDS = {"NAME", "SOURCES", "PUBLIC_DEPS", "PRIVATE_DEPS"}
LINK_KEYWORDS = {"PUBLIC", "PRIVATE", "INTERFACE"}


def check_cmake(root, folder, deps, findings):
    path = os.path.join(root, folder, "CMakeLists.txt")
    rel = os.path.relpath(path, root)
    if not os.path.isfile(path):
        findings.append(Finding(os.path.join(folder, ""), 1, f"{folder} has no CMakeLists.txt (every library "
                                "folder builds one svbtdf_add_library target)"))
        return
    with open(path, encoding="utf-8") as f:
        text = f.read()

    def check_dep(token, number):
        m = re.fullmatch(r"svbtdf::([A-Za-z0-9_]+)", token.strip('"'))
        if m and m.group(1) != folder and m.group(1) not in deps:
            findings.append(Finding(rel, number, f"{folder} may not link {m.group(0)} "
                                    f"(allowed: {allowed_text(folder, deps)})"))

    for command, args in cmake_calls(text):
        if command == "svbtdf_add_library":
            keyword = None
            for token, number in args:
                if token in ADD_LIBRARY_KEYWORDS:
                    keyword = token
                elif keyword == "NAME" and token != folder:
                    findings.append(Finding(rel, number, f"the library of {folder}/ is named {token}; "
                                            f"it must be named {folder}"))
                elif keyword in ("PUBLIC_DEPS", "PRIVATE_DEPS"):
                    check_dep(token, number)
        elif command == "target_link_libraries" and args and args[0][0] in (f"svbtdf_{folder}", f"svbtdf::{folder}"):
            for token, number in args[1:]:
                if token not in LINK_KEYWORDS:
                    check_dep(token, number)


def check(root):
    """Checks the tree at root; returns (findings, stats)."""
    findings, stats = [], {"files": 0, "includes": 0}
    doc_path = os.path.join(root, ARCHITECTURE_DOC)
    if not os.path.isfile(doc_path):
        return [Finding(ARCHITECTURE_DOC, 1, "missing: the layers table lives there")], stats
    table, text = parse_layers(doc_path, ARCHITECTURE_DOC, findings)
    if not table:
        return findings, stats
    check_mermaid(text, ARCHITECTURE_DOC, table, findings)
    libraries = {f for f, deps in table.items() if deps != EVERYTHING}

    for name in sorted(os.listdir(root)):
        if name.startswith(".") or name in table:
            continue
        if os.path.isdir(os.path.join(root, name, "include", "svbtdf")):
            findings.append(Finding(os.path.join(name, ""), 1, f"{name}/ is a library folder (it has "
                                    f"include/svbtdf/) but is not in the layers block of {ARCHITECTURE_DOC}"))

    for folder, deps in table.items():
        top = os.path.join(root, folder)
        if not os.path.isdir(top):
            continue  # in the table but not on disk (yet, or no longer): skipped silently
        if deps == EVERYTHING:
            for path in source_files(top):
                check_includes(root, path, folder, deps, libraries, findings, stats)
            continue
        check_header_places(root, folder, findings)
        for sub in ("include", "src"):
            for path in source_files(os.path.join(top, sub)):
                check_includes(root, path, folder, deps, libraries, findings, stats)
                check_namespaces(root, path, folder, deps, findings)
        check_cmake(root, folder, deps, findings)
    return findings, stats


def run(root):
    findings, stats = check(root)
    for finding in findings:
        print(finding)
    if findings:
        print(f"layers: {len(findings)} violation(s) in {stats['files']} files, "
              f"{stats['includes']} includes (the layers are in {ARCHITECTURE_DOC})")
        return 1
    print(f"layers: {stats['files']} files, {stats['includes']} includes, all one way")
    return 0


# ----------------------------------------------------------------------------------------------
# Self-test: fake trees with known faults; the check must report exactly those.

FAKE_DOC = """# fake

```layers
common:            # the bottom
model: common
session: common
fit: model, common
cli: *
```

```mermaid
graph TD
  cli --> fit
  fit --> model
  model --> common
  cli --> session
  session --> common
```
"""

FAKE_CMAKE = """svbtdf_add_library(
  NAME {name}
  SOURCES src/a.cc
  PUBLIC_DEPS {public}
  PRIVATE_DEPS {private}
)
"""


def write(root, rel, text):
    path = os.path.join(root, rel)
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w", encoding="utf-8") as f:
        f.write(text)


def fake_tree(root):
    """A clean tree: common <- model <- fit, session <- cli (session absent: not moved yet...)."""
    write(root, ARCHITECTURE_DOC, FAKE_DOC)
    write(root, "common/include/svbtdf/common/error.h", "#pragma once\n")
    write(root, "common/src/error.cc", '#include "svbtdf/common/error.h"\n')
    write(root, "common/CMakeLists.txt", FAKE_CMAKE.format(name="common", public="Eigen3::Eigen", private=""))
    write(root, "model/include/svbtdf/model/ggx.h", '#pragma once\n#include "svbtdf/common/error.h"\n')
    write(root, "model/src/ggx.cc", '#include "svbtdf/model/ggx.h"\n\n#include <vector>\n\n'
          'namespace svbtdf::common {\nclass Error;\n}\n\nnamespace svbtdf::model {\nnamespace {\n}\n}\n')
    write(root, "model/CMakeLists.txt", FAKE_CMAKE.format(name="model", public="svbtdf::common", private=""))
    write(root, "fit/include/svbtdf/fit/fit.h", '#pragma once\n#include "svbtdf/model/ggx.h"\n')
    write(root, "fit/src/fit.cc", '#include "svbtdf/fit/fit.h"\n#include <svbtdf/common/error.h>\n')
    write(root, "fit/CMakeLists.txt", FAKE_CMAKE.format(name="fit", public="svbtdf::model\n    svbtdf::common",
                                                        private="Ceres::ceres"))
    write(root, "cli/main.cc", '#include "svbtdf/fit/fit.h"\n#include "svbtdf/session/session.h"\n')
    write(root, "build/svbtdf/fit/fit.cc", '#include "svbtdf/cli/nothing.h"\n')  # not a table folder


def self_test():
    failures = []

    def expect(name, got, want):
        if got != want:
            failures.append(f"{name}:\n  got  {got!r}\n  want {want!r}")

    with tempfile.TemporaryDirectory(prefix="check_layers_") as tmp:
        # 1. Clean tree: exit 0, the summary line (session/ is in the table but absent: skipped).
        clean = os.path.join(tmp, "clean")
        fake_tree(clean)
        findings, stats = check(clean)
        expect("clean tree findings", [str(f) for f in findings], [])
        expect("clean tree stats", stats, {"files": 7, "includes": 8})

        # 2. One good and one bad include, run as a program: exactly the bad one, with file:line.
        bad = os.path.join(tmp, "bad")
        fake_tree(bad)
        write(bad, "common/src/error.cc",
              '#include "svbtdf/common/error.h"\n\n#include "svbtdf/model/ggx.h"  // upwards\n')
        proc = subprocess.run([sys.executable, os.path.abspath(__file__), "--root", bad],
                              capture_output=True, text=True)
        expect("bad include exit status", proc.returncode, 1)
        expect("bad include output", proc.stdout.splitlines()[:-1],
               [os.path.join("common", "src", "error.cc") + ":3: common may not include svbtdf/model/ggx.h "
                "(allowed: common itself only)"])
        proc = subprocess.run([sys.executable, os.path.abspath(__file__), "--root", clean],
                              capture_output=True, text=True)
        expect("clean tree as a program", (proc.returncode, proc.stdout),
               (0, "layers: 7 files, 8 includes, all one way\n"))

        # 3. The other rules: a misfiled header, a CMake dependency upwards, an unlisted library,
        #    a sideways include, an unknown module from the command line, a wrong picture.
        other = os.path.join(tmp, "other")
        fake_tree(other)
        write(other, "model/include/svbtdf/common/statistics.h", "#pragma once\n")
        write(other, "model/CMakeLists.txt",
              FAKE_CMAKE.format(name="model", public="svbtdf::common", private="svbtdf::fit ZLIB::ZLIB"))
        write(other, "report/include/svbtdf/report/compare.h", "#pragma once\n")
        write(other, "fit/src/fit.cc", '#include "svbtdf/fit/fit.h"\n#include "svbtdf/session/session.h"\n'
              'namespace svbtdf {\n}\nnamespace svbtdf::session::detail {\n}\nnamespace svbtdf::fit::store {\n}\n')
        write(other, "cli/main.cc", '#include "svbtdf/fit/fit.h"\n#include "svbtdf/processs/x.h"\n')
        write(other, ARCHITECTURE_DOC, FAKE_DOC.replace("  fit --> model\n", "  fit --> session\n"))
        findings, _ = check(other)
        expect("other rules", sorted(str(f) for f in findings), sorted([
            f"{ARCHITECTURE_DOC}:12: the mermaid picture disagrees with the layers block for fit: "
            "draws session not in the table; lacks model",
            f"{ARCHITECTURE_DOC}:12: the mermaid picture does not connect cli to every library (missing: model)",
            os.path.join("cli", "main.cc") + f":2: svbtdf/processs/ is no library folder of {ARCHITECTURE_DOC} "
            "(included as svbtdf/processs/x.h)",
            os.path.join("fit", "src", "fit.cc") + ":2: fit may not include svbtdf/session/session.h "
            "(allowed: fit itself, common, model)",
            os.path.join("fit", "src", "fit.cc") + ":3: namespace svbtdf is no room's; fit/ declares its names "
            "in svbtdf::fit",
            os.path.join("fit", "src", "fit.cc") + ":5: fit/ opens namespace svbtdf::session, a room it may not "
            "include (allowed: fit itself, common, model)",
            os.path.join("model", "CMakeLists.txt") + ":5: model may not link svbtdf::fit "
            "(allowed: model itself, common)",
            os.path.join("model", "include", "svbtdf", "common", "statistics.h") +
            ":1: svbtdf/common/ headers belong in common/include, not model/include",
            os.path.join("report", "") + f":1: report/ is a library folder (it has include/svbtdf/) but is "
            f"not in the layers block of {ARCHITECTURE_DOC}",
        ]))

        # 4. The table itself: a cycle is refused.
        cyclic = os.path.join(tmp, "cyclic")
        fake_tree(cyclic)
        write(cyclic, ARCHITECTURE_DOC, FAKE_DOC.replace("common:            # the bottom", "common: fit"))
        findings, _ = check(cyclic)
        expect("cycle found", any("cycle" in f.message for f in findings), True)

    if failures:
        print("check_layers self-test FAILED:")
        for failure in failures:
            print(failure)
        return 1
    print("check_layers self-test: 4 fake trees, every finding as expected")
    return 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--root", default=os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                        help="the tree to check (default: the one this script lives in)")
    parser.add_argument("--self-test", action="store_true", help="test the check on fake trees and exit")
    args = parser.parse_args()
    if args.self_test:
        return self_test()
    if not os.path.isdir(args.root):
        print(f"check_layers: no such folder {args.root}", file=sys.stderr)
        return 2
    return run(args.root)


if __name__ == "__main__":
    sys.exit(main())
