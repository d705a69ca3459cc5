#!/usr/bin/env python3
"""Every option the library names in a message (option_name("...") under src/) has a flag in
the CLI's table (cli_option_name in apps/trochomill/cli_common.cpp), so the CLI never shows an
API name where its users typed a flag.

    python3 tests/docs/option-names.py SOURCE_DIR"""
import pathlib
import re
import sys

root = pathlib.Path(sys.argv[1])
used = {}
for f in sorted((root / "src").rglob("*.[ch]pp")):
    text = f.read_text()
    for m in re.finditer(r'option_name\(([^;]*?)\)', text):
        for name in re.findall(r'"([a-z_0-9]+)"', m.group(1)):
            used.setdefault(name, f.relative_to(root))
table = (root / "apps/trochomill/cli_common.cpp").read_text()
mapped = set(re.findall(r'\{"([a-z_0-9]+)", "--[a-z-]+"\}', table))
missing = sorted(n for n in used if n not in mapped)
for n in missing:
    print("FAIL %s (%s) has no CLI flag in cli_option_name" % (n, used[n]))
if len(used) < 20:
    print("FAIL only %d option names found under src/: the scan is broken" % len(used))
    sys.exit(1)
print("%d option names, each with a CLI flag" % len(used) if not missing else "")
sys.exit(1 if missing else 0)
