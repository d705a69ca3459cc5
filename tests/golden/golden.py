#!/usr/bin/env python3
"""The golden figures: the examples' headline numbers, each with the command that gives it.

tests/golden/figures.toml holds them (value as published, to `digits` significant digits);
the docs quote them between markers, <!--fig:NAME-->VALUE<!--/fig-->, so a figure is written
in one place and the docs follow it.

  golden.py check TROCHOMILL        every figure's command gives its value (to its digits),
                                    and every marker in the docs holds its figure's value
  golden.py write TROCHOMILL --reason "why"
                                    the table takes the measured values; each figure that
                                    changed gets `since = "DATE: why"` (the commit that
                                    changes a figure says why, in the table)
  golden.py docs                    the docs' markers rewritten from the table

A figure that moves fails `check` until the table (with its reason) and the docs are updated
in the same commit. Exit 0 when all hold, 1 otherwise, 2 for a bad table.
"""
import datetime
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
TABLE = os.path.join(HERE, "figures.toml")
DOCS = ["README.md", "docs/models.md", "docs/user-guide.md", "docs/PERFORMANCE.md",
        "docs/python.md", "docs/gcode.md"]
MARKER = re.compile(r"<!--fig:([a-z0-9-]+)-->(.*?)<!--/fig-->")
# The whole table as docs/models.md shows it, between these lines.
BLOCK = ("docs/models.md", "<!-- golden:begin -->", "<!-- golden:end -->")


def load():
    with open(TABLE, "rb") as f:
        t = tomllib.load(f)
    figs = t.get("figure", [])
    names = set()
    for f in figs:
        for k in ("name", "what", "command", "value", "unit", "since"):
            if k not in f:
                sys.exit(f"golden: {TABLE}: figure {f.get('name', '?')}: no '{k}'")
        if ("key" in f) == ("pattern" in f):
            sys.exit(f"golden: {TABLE}: figure {f['name']}: give one of 'key' and 'pattern'")
        if f["name"] in names:
            sys.exit(f"golden: {TABLE}: figure {f['name']} twice")
        names.add(f["name"])
    return figs


def fmt(x, digits):
    """x to `digits` significant digits, as the docs print it (no exponent, trailing zeros
    kept: 0.05000 is five digits)."""
    if x == 0:
        return "0"
    s = f"{x:.{digits}g}"
    if "e" in s:  # write out what %g put in an exponent
        exp = int(s.split("e")[1])
        decimals = max(0, digits - 1 - exp)
        s = f"{x:.{decimals}f}"
    if "." not in s and len(s.lstrip("-")) < digits:
        s += "." + "0" * (digits - len(s.lstrip("-")))
    elif "." in s:
        sig = len(s.lstrip("-").replace(".", "").lstrip("0"))
        if sig < digits:
            s += "0" * (digits - sig)
    return s


def run_all(cli, figs):
    """Each distinct command once: {command: (stdout, parsed JSON or None)}."""
    out = {}
    with tempfile.TemporaryDirectory() as tmp:
        for f in figs:
            cmd = f["command"]
            if cmd in out:
                continue
            args = [a.replace("{tmp}", tmp) for a in shlex.split(cmd)]
            r = subprocess.run([cli, *args], cwd=ROOT, capture_output=True, text=True)
            if r.returncode != 0:
                print(f"golden: `trochomill {cmd}` exited {r.returncode}: {r.stderr.strip()}")
                out[cmd] = None
                continue
            parsed = None
            if "--json -" in cmd:
                parsed = json.loads(r.stdout)
            out[cmd] = (r.stdout, parsed)
    return out


def measure(f, results):
    res = results.get(f["command"])
    if res is None:
        return None
    text, parsed = res
    if "key" in f:
        v = parsed
        for part in f["key"].split("."):
            if not isinstance(v, dict) or part not in v:
                return None
            v = v[part]
        return float(v) if isinstance(v, (int, float)) else None
    m = re.search(f["pattern"], text)
    return float(m.group(1)) if m else None


def block(figs):
    """The table for docs/models.md: figure, value and unit, the command, since when."""
    rows = ["| figure | value | command | since |", "|---|---|---|---|"]
    for f in figs:
        unit = f" {f['unit']}" if f["unit"] else ""
        where = (f"`{f['command']}`" + (f" ({f['key']})" if "key" in f else "")).replace(
            "|", "\\|")
        rows.append(f"| {f['what']} | {f['value']}{unit} | {where} | {f['since']} |")
    return "\n".join(rows) + "\n"


def block_span(text):
    _, begin, end = BLOCK
    i, j = text.find(begin), text.find(end)
    if i < 0 or j < i:
        return None
    return i + len(begin) + 1, j


def check_docs(figs):
    by = {f["name"]: f for f in figs}
    bad = []
    text = open(os.path.join(ROOT, BLOCK[0]), encoding="utf-8").read()
    span = block_span(text)
    if span is None:
        bad.append(f"{BLOCK[0]}: no {BLOCK[1]} ... {BLOCK[2]} block")
    elif text[span[0]:span[1]] != block(figs):
        bad.append(f"{BLOCK[0]}: the golden table differs from the figures (golden.py docs)")
    for d in DOCS:
        path = os.path.join(ROOT, d)
        if not os.path.exists(path):
            continue
        for n, line in enumerate(open(path, encoding="utf-8"), 1):
            for m in MARKER.finditer(line):
                name, shown = m.group(1), m.group(2)
                if name not in by:
                    bad.append(f"{d}:{n}: fig:{name} is not in the table")
                elif shown != by[name]["value"]:
                    bad.append(f"{d}:{n}: fig:{name} shows {shown}, the table {by[name]['value']}"
                               " (golden.py docs)")
    return bad


def write_docs(figs):
    by = {f["name"]: f["value"] for f in figs}
    for d in DOCS:
        path = os.path.join(ROOT, d)
        if not os.path.exists(path):
            continue
        text = open(path, encoding="utf-8").read()
        if d == BLOCK[0]:
            span = block_span(text)
            if span is not None:
                text = text[:span[0]] + block(figs) + text[span[1]:]
        new = MARKER.sub(lambda m: f"<!--fig:{m.group(1)}-->{by.get(m.group(1), m.group(2))}"
                         "<!--/fig-->", text)
        if new != open(path, encoding="utf-8").read():
            open(path, "w", encoding="utf-8").write(new)
            print(f"golden: {d} updated")


def toml_str(s):
    return json.dumps(s, ensure_ascii=False)


def write_table(figs, header):
    keys = ["name", "what", "command", "key", "pattern", "digits", "unit", "value", "since"]
    with open(TABLE, "w", encoding="utf-8") as out:
        out.write(header)
        for f in figs:
            out.write("\n[[figure]]\n")
            for k in keys:
                if k in f:
                    v = f[k]
                    out.write(f"{k} = {v if isinstance(v, int) else toml_str(v)}\n")


def main():
    if len(sys.argv) < 2 or sys.argv[1] not in ("check", "write", "docs"):
        print(__doc__)
        return 2
    figs = load()
    if sys.argv[1] == "docs":
        write_docs(figs)
        return 0
    if len(sys.argv) < 3:
        print(__doc__)
        return 2
    cli = sys.argv[2]
    results = run_all(cli, figs)
    failures = []
    changed = []
    for f in figs:
        got = measure(f, results)
        digits = f.get("digits", 4)
        if got is None:
            failures.append(f"{f['name']}: `trochomill {f['command']}` gave no "
                            f"{f.get('key', f.get('pattern'))}")
            continue
        shown = fmt(got, digits)
        if shown != f["value"]:
            failures.append(f"{f['name']} ({f['what']}): {shown} {f['unit']}, the table says "
                            f"{f['value']} (since {f['since']}); `trochomill {f['command']}`")
            changed.append((f, shown))
    if sys.argv[1] == "write":
        if "--reason" not in sys.argv:
            print("golden: write needs --reason \"why the figures moved\"")
            return 2
        reason = sys.argv[sys.argv.index("--reason") + 1]
        today = datetime.date.today().isoformat()
        for f, shown in changed:
            f["value"] = shown
            f["since"] = f"{today}: {reason}"
        header = open(TABLE, encoding="utf-8").read().split("\n[[figure]]")[0]
        write_table(figs, header.rstrip("\n") + "\n")
        print(f"golden: {len(changed)} figures written")
        return 0
    failures += check_docs(figs)
    for line in failures:
        print("FAIL:", line)
    print(f"golden: {len(figs)} figures, {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
