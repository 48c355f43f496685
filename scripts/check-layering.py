#!/usr/bin/python3
"""The module graph as built, checked: every library in src/ declares what it links
(rotorguard_module(... DEPENDS ...) in its CMakeLists.txt); this script checks that

  - the modules' dependencies form no cycle,
  - every file of a module includes headers only of itself and of the modules it links,
    directly or through them (the build enforces it too, but only for the headers a file
    happens to include today),
  - no header include graph in src/ has a cycle,

and prints the graph (`--graph`), each module with what it links directly. Exit 1 on a violation,
naming the file and the include. `--self-test` first shows, on made-up trees, that each check fails
when it should. Standard library only.

    scripts/check-layering.py [--graph] [--self-test]
"""
import os
import re
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
INCLUDE = re.compile(r'^#include "rotorguard/([a-z0-9_]+)/([a-z0-9_]+\.h)"', re.M)


class Violation(Exception):
    pass


def modules(src):
    """Module name -> the modules it links (DEPENDS and PRIVATE_DEPENDS), from the CMakeLists."""
    deps = {}
    for name in sorted(os.listdir(src)):
        cmake = os.path.join(src, name, "CMakeLists.txt")
        if not os.path.exists(cmake):
            continue
        text = open(cmake).read()
        m = re.search(r"rotorguard_module\((\w+)(.*?)\)", text, re.S)
        if not m:
            continue
        deps[m.group(1)] = sorted(set(re.findall(r"rotorguard::(\w+)", m.group(2))))
    return deps


def closure(deps):
    reach = {}

    def visit(m, stack):
        if m in stack:
            raise Violation("module cycle: " + " -> ".join(stack[stack.index(m):] + [m]))
        if m in reach:
            return reach[m]
        out = set()
        for d in deps.get(m, []):
            out |= {d} | visit(d, stack + [m])
        reach[m] = out
        return out

    for m in deps:
        visit(m, [])
    return reach


def files_of(src, module):
    for folder, _, names in os.walk(os.path.join(src, module)):
        for n in names:
            if n.endswith((".h", ".cc")):
                yield os.path.join(folder, n)


def check(root):
    """The violations in the tree at `root` (an empty list when there are none), and the graph."""
    src = os.path.join(root, "src")
    deps = modules(src)
    try:
        reach = closure(deps)
    except Violation as v:
        return [str(v)], deps
    errors = []
    graph = {}  # file -> headers it includes
    for module in deps:
        for path in files_of(src, module):
            rel = os.path.relpath(path, root)
            for m in INCLUDE.finditer(open(path).read()):
                other, header = m.group(1), m.group(2)
                if other != module and other not in reach[module]:
                    errors.append(f"{rel}: includes rotorguard/{other}/{header}, but {module} does not link {other}")
                graph.setdefault(rel, []).append(f"src/{other}/include/rotorguard/{other}/{header}")
    state = {}  # depth-first search: 1 on the path, 2 done

    def dfs(node, path):
        state[node] = 1
        for nxt in graph.get(node, []):
            if state.get(nxt) == 1:
                errors.append("include cycle: " + " -> ".join(path[path.index(nxt):] + [nxt]))
            elif state.get(nxt) is None:
                dfs(nxt, path + [nxt])
        state[node] = 2

    for node in list(graph):
        if state.get(node) is None:
            dfs(node, [node])
    return errors, deps


def self_test():
    """Each check on made-up trees: a module cycle, an include of an unlinked module, a header cycle."""
    def tree(modules_and_files):
        root = tempfile.mkdtemp(prefix="layering-")
        for path, text in modules_and_files.items():
            full = os.path.join(root, "src", path)
            os.makedirs(os.path.dirname(full), exist_ok=True)
            with open(full, "w") as f:
                f.write(text)
        return root
    cycle = tree({"a/CMakeLists.txt": "rotorguard_module(a DEPENDS rotorguard::b)",
                  "b/CMakeLists.txt": "rotorguard_module(b DEPENDS rotorguard::a)"})
    unlinked = tree({"a/CMakeLists.txt": "rotorguard_module(a SOURCES a.cc)",
                     "b/CMakeLists.txt": "rotorguard_module(b SOURCES b.cc)",
                     "a/a.cc": '#include "rotorguard/b/b.h"\n'})
    headers = tree({"a/CMakeLists.txt": "rotorguard_module(a SOURCES a.cc)",
                    "a/include/rotorguard/a/x.h": '#include "rotorguard/a/y.h"\n',
                    "a/include/rotorguard/a/y.h": '#include "rotorguard/a/x.h"\n'})
    clean = tree({"a/CMakeLists.txt": "rotorguard_module(a DEPENDS rotorguard::b)",
                  "b/CMakeLists.txt": "rotorguard_module(b SOURCES b.cc)",
                  "a/a.cc": '#include "rotorguard/b/b.h"\n'})
    for name, root, expected in [("module cycle", cycle, "module cycle"), ("unlinked include", unlinked, "does not link"),
                                 ("header cycle", headers, "include cycle"), ("clean tree", clean, None)]:
        errors, _ = check(root)
        found = any(expected in e for e in errors) if expected else not errors
        if not found:
            print(f"self-test failed: {name}: {errors}", file=sys.stderr)
            return False
    return True


def main():
    if "--self-test" in sys.argv and not self_test():
        return 1
    errors, deps = check(ROOT)
    if "--graph" in sys.argv:
        for m, d in deps.items():
            print(f"{m}: {', '.join(d) if d else '(none)'}")
    for e in errors:
        print(e, file=sys.stderr)
    if errors:
        return 1
    print(f"{len(deps)} modules, no cycle; every include within what its module links", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
