#!/usr/bin/env python3
"""The drawing of nec's libraries from their #include lines, and the check that every arrow points down.

    python3 scripts/include_graph.py           # the libraries by level, each with what it includes
    python3 scripts/include_graph.py --dot     # the same as a Graphviz digraph
    python3 scripts/include_graph.py --check   # exit 1 naming the file and line of any include that points
                                               # sideways or up (CTest runs this)

A library is a top-level folder; an include "nec/NAME/..." is an arrow to library NAME. LEVELS is the intended
layering (docs/layout.md): a library may include only libraries of lower levels. tests/ and benchmarks/ sit
above everything and are not drawn.
"""
import pathlib
import re
import sys

LEVELS = {
    "motion": 0,                                              # what a motion is
    "corpus": 1, "fitting": 1, "assets": 1, "zoo": 1,         # built on the core alone
    "layers": 2, "train": 2, "viewer": 2,
    "text": 3, "studio": 3,
    "owo": 4,
    "tat": 5,
    "evaluator": 6, "gpt": 6, "diffusion": 6,
    "apps": 7,
}
INCLUDE = re.compile(r'^\s*#\s*include\s+"nec/([a-z_]+)/')


def arrows(root):
    """(library, included library, file, line) for every include of another library's header."""
    for path in sorted(root.rglob("*")):
        if path.suffix not in (".h", ".cpp") or not path.is_file():
            continue
        library = path.relative_to(root).parts[0]
        if library not in LEVELS:
            continue
        for number, text in enumerate(path.read_text(encoding="utf-8", errors="replace").splitlines(), 1):
            match = INCLUDE.match(text)
            if match and match.group(1) != library:
                yield library, match.group(1), path.relative_to(root), number


def main(argv):
    root = pathlib.Path(__file__).resolve().parent.parent
    found = list(arrows(root))
    graph = {library: set() for library in LEVELS}
    for library, target, _, _ in found:
        graph[library].add(target)
    if "--check" in argv:
        wrong = [(library, target, path, line) for library, target, path, line in found
                 if target not in LEVELS or LEVELS[target] >= LEVELS[library]]
        for library, target, path, line in wrong:
            where = "an unknown library" if target not in LEVELS else f"level {LEVELS[target]}"
            print(f"{path}:{line}: {library} (level {LEVELS[library]}) includes nec/{target}/ ({where}): "
                  "arrows must point to lower levels (scripts/include_graph.py LEVELS, docs/layout.md)")
        missing = sorted(name for name in LEVELS if not (root / name).is_dir())
        for name in missing:
            print(f"include_graph: library folder {name}/ does not exist")
        print(f"include_graph: {len(found)} includes across libraries, {len(wrong)} pointing sideways or up")
        return 1 if wrong or missing else 0
    if "--dot" in argv:
        print("digraph nec {\n  rankdir=BT;")
        for library in LEVELS:
            for target in sorted(graph[library]):
                print(f'  "{library}" -> "{target}";')
        print("}")
        return 0
    for level in sorted(set(LEVELS.values()), reverse=True):
        for library in sorted(name for name, value in LEVELS.items() if value == level):
            below = ", ".join(sorted(graph[library], key=lambda t: (-LEVELS.get(t, -1), t))) or "-"
            print(f"{level}  {library:<10} -> {below}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
