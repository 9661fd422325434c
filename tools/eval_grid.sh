#!/usr/bin/env bash
# Accuracy and speed of several solver configurations in one go: each configuration is
# evaluated on the clean and the T265-like development pairs and timed on one real pair,
# one summary line each (mean tau>1 / tau>3 % of the binocular pairs, per-pair tau>1,
# mean non-occluded tau>1 of the forward pairs, frame and sweep medians). This is how the
# presets' schedules were chosen (docs/accuracy.md "How realtime was chosen").
#
#   tools/eval_grid.sh CLI BACKEND DATA CONFIGS [REALPAIR]
#
# DATA holds synthetic/ and synthetic_real/ (../shared/data); CONFIGS has one
# configuration a line, "name|flags" (e.g. "taper5|--preset realtime --warps-taper 5");
# REALPAIR (default DATA/t265/robot) holds camchain.yaml, left.png, right.png for the
# timing (RUNS=15 frames). The CSVs go to $GRID_OUT (default: a temporary folder).
set -euo pipefail
cli=$1 backend=$2 data=$3 configs=$4 real=${5:-$3/t265/robot}
out=${GRID_OUT:-$(mktemp -d)}
mkdir -p "$out"
while IFS='|' read -r name flags; do
  [ -z "$name" ] && continue
  read -ra extra <<< "$flags"
  for kind in synthetic synthetic_real; do
    log="$out/$name.$kind.log"
    "$cli" eval "$data/$kind"/*/ --backend "$backend" "${extra[@]}" --csv "$out/$name.$kind.csv" > "$log" 2>&1 ||
      { tail -3 "$log" >&2; exit 1; }
  done
  timing=$("$cli" bench --backend "$backend" --calib "$real/camchain.yaml" "$real/left.png" "$real/right.png" \
    "${extra[@]}" --runs "${RUNS:-15}" 2>/dev/null |
    awk '/^frame:/{f=$3} /^sweep:/{s+=$3} END{printf "frame %s ms, sweep %.2f ms", f, s}')
  python3 - "$name" "$flags" "$out" "$timing" <<'PY'
import csv, sys
name, flags, out, timing = sys.argv[1:5]
def mean(rows, key): return sum(float(r[key]) for r in rows) / len(rows)
parts = []
for kind, label in (("synthetic", "clean"), ("synthetic_real", "T265-like")):
    rows = [r for r in csv.DictReader(open(f"{out}/{name}.{kind}.csv")) if r["method"] == "ours"]
    bino = [r for r in rows if r["pair"].startswith("bino")]
    fwd = [r for r in rows if r["pair"].startswith("temp")]
    each = " ".join("%.1f" % float(r["tau1"]) for r in bino)
    parts.append(f"{label}: bino {mean(bino, 'tau1'):.1f} / {mean(bino, 'tau3'):.1f} [{each}]"
                 + (f", fwd noc {mean(fwd, 'tau1_noc'):.1f}" if fwd else ""))
print(f"{name:12s} {flags:48s} {' | '.join(parts)} | {timing}")
PY
done < "$configs"
