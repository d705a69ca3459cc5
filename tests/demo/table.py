#!/usr/bin/env python3
"""The demo's Wagih table (`scripts/demo BIN OUT --wagih-table`, what `make demo` prints): one
row per family, every column the family's own `analyze --json` value (run here on its own, not
read from the demo's files) printed as the demo prints it, and no column of zeros (the demo once
read keys that analyze had renamed and printed 0.0000 for all four families).
Usage: table.py TROCHOMILL WORK_DIR"""
import json
import os
import subprocess
import sys

cli, work = sys.argv[1], sys.argv[2]
root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
os.makedirs(work, exist_ok=True)
out = subprocess.run(["bash", os.path.join(root, "scripts/demo"), cli, work, "--wagih-table"],
                     cwd=root, capture_output=True, text=True, check=True).stdout
# The columns and the demo's formats (scripts/demo, wagih_table).
columns = [(key, "%.4g") for key in [
    "cycle_time_s", "cycle_cutting_time_s", "cycle_cooling_time_s", "cycle_mrr_mm3_per_min",
    "mrr_total_mm3_per_min", "cycle_h_max_mm", "cycle_t_h_max_s", "cycle_engagement_angle_max_deg",
    "waviness_left_mm", "waviness_right_mm", "waviness_left_tooth_mm", "waviness_right_tooth_mm",
    "cycle_force_max_predicted_n"]]
families = ["trochoidal", "circular", "elliptical", "linear-elliptical"]
rows = {line.split()[0]: line.split()[1:] for line in out.splitlines()
        if line.split() and line.split()[0] in families}
failures = []
if sorted(rows) != sorted(families):
    failures.append(f"rows {sorted(rows)}, want {families}:\n{out}")
for fam in families:
    if fam not in rows:
        continue
    r = subprocess.run([cli, "analyze", f"examples/wagih2023/{fam}.toml", "--json", "-"],
                       cwd=root, capture_output=True, text=True, check=True)
    j = json.loads(r.stdout)
    if len(rows[fam]) != len(columns):
        failures.append(f"{fam}: {len(rows[fam])} columns, want {len(columns)}")
        continue
    for (key, f), shown in zip(columns, rows[fam]):
        want = f % j[key]
        if shown != want:
            failures.append(f"{fam} {key}: the demo prints {shown}, analyze gives {want}")
for c, (key, f) in enumerate(columns):
    vals = [float(rows[fam][c]) for fam in families if fam in rows and len(rows[fam]) > c]
    if vals and all(v == 0 for v in vals):
        failures.append(f"{key}: a column of zeros")
for line in failures:
    print("FAIL:", line)
print(out)
print(f"{len(failures)} failures")
sys.exit(1 if failures else 0)
