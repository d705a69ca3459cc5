#!/usr/bin/env python3
"""docs/architecture.md's table of modules names, for each module, the modules it uses: the
same as the build declares (trochomill_module(... DEPENDS ...), written by CMake to
layers.cmake). Usage: module-table.py ROOT BUILD_DIR"""
import re
import sys

root, build = sys.argv[1], sys.argv[2]
declared = {}
modules = []
for line in open(f"{build}/layers.cmake"):
    m = re.match(r"set\(MODULES (.*)\)", line)
    if m:
        modules = m.group(1).replace(";", " ").split()
    m = re.match(r"set\(DEPENDS_(\w+) ?(.*)\)", line)
    if m:
        declared[m.group(1)] = set(m.group(2).replace(";", " ").split())

documented = {}
for line in open(f"{root}/docs/architecture.md"):
    m = re.match(r"\| `(\w+)` \|.*\| ([^|]*) \|\s*$", line)
    if m and m.group(1) in modules:
        uses = m.group(2).strip()
        documented[m.group(1)] = set() if uses == "-" else {u.strip() for u in uses.split(",")}

problems = []
for mod in modules:
    if mod not in documented:
        problems.append(f"module {mod} has no row in the table of docs/architecture.md")
    elif documented[mod] != declared.get(mod, set()):
        problems.append(f"module {mod}: the table says it uses {sorted(documented[mod])}, "
                        f"CMakeLists.txt declares {sorted(declared.get(mod, set()))}")
for p in problems:
    print(p)
print(f"{len(modules)} modules, {len(problems)} differences")
sys.exit(1 if problems else 0)
