#!/usr/bin/env bash
# The shifted-world equivalence (issue 11): the tiny world simulated twice, once as is and once with every
# pose shifted by a UTM-size offset (scans unchanged, as a GNSS-posed drive), goes through build-map,
# inspect, evaluate and localize. The shifted map's origin is the unshifted one plus the offset, its
# sections are the same bytes, success counts and errors are the same, the map-local poses agree and the
# map-frame poses differ by exactly the offset. Host builds (runs the built tool).
set -u
gsf=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
east=512345
north=5412345
for w in local utm; do
  offset=0,0
  [ "$w" = utm ] && offset=$east,$north
  "$gsf" simulate --preset tiny --out "$tmp/$w" --offset "$offset" --quiet >/dev/null || fail "simulate $w"
  "$gsf" build-map --dataset "$tmp/$w" --out "$tmp/$w.gsfmap" --quiet > "$tmp/$w.build.txt" || fail "build-map $w"
  "$gsf" inspect --map "$tmp/$w.gsfmap" --json > "$tmp/$w.inspect.json" || fail "inspect $w"
  "$gsf" evaluate --map "$tmp/$w.gsfmap" --dataset "$tmp/$w" --mode all --json "$tmp/$w.eval.json" \
    --quiet >/dev/null || fail "evaluate $w"
  "$gsf" localize --map "$tmp/$w.gsfmap" --dataset "$tmp/$w" > "$tmp/$w.localize.jsonl" || fail "localize $w"
done
cmp -s "$tmp/local/sequences/01/velodyne/000003.bin" "$tmp/utm/sequences/01/velodyne/000003.bin" || fail "scans differ"
# Everything after the 624-byte header and section table: instances, fields, triangles, layers.
cmp -s <(tail -c +625 "$tmp/local.gsfmap") <(tail -c +625 "$tmp/utm.gsfmap") || fail "map sections differ"
python3 - "$tmp" "$east" "$north" <<'PY' || exit 1
import json, sys
t, east, north = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
ins = {w: json.load(open(f"{t}/{w}.inspect.json")) for w in ("local", "utm")}
lo, ut = ins["local"]["origin"], ins["utm"]["origin"]
# The tiny drive starts at (0, -2.5, 1.73): origin (0, -2, 2) rounded half up, shifted exactly.
assert lo == [0, -2, 2], lo
assert ut == [lo[0] + east, lo[1] + north, lo[2]], ut
assert ins["utm"]["bytes"] == ins["local"]["bytes"]
ev = {w: json.load(open(f"{t}/{w}.eval.json")) for w in ("local", "utm")}
assert ev["utm"]["map_origin"] == ut
summary = []
for mode in ("instance", "gsf", "gsf+refine", "scan-context"):
    a, b = ev["local"]["modes"][mode], ev["utm"]["modes"][mode]
    assert a["summary"]["successes"] == b["summary"]["successes"], (mode, a["summary"]["successes"], b["summary"]["successes"])
    assert a["summary"]["answered"] == b["summary"]["answered"], mode
    if mode != "scan-context":  # the peer needs no map; it is here for the dataset-frame comparison
        assert a["summary"]["successes"] >= 20, (mode, a["summary"]["successes"])  # working, not 0 == 0
    for qa, qb in zip(a["queries"], b["queries"]):
        assert qa["status"] == qb["status"] and qa["success"] == qb["success"], (mode, qa["index"])
        assert abs(qa["translation_error_m"] - qb["translation_error_m"]) < 1e-6, (mode, qa["index"])
        assert abs(qa["rotation_error_deg"] - qb["rotation_error_deg"]) < 1e-6, (mode, qa["index"])
        if "pose" in qa:
            d = [qb["pose"][4 * r + 3] - qa["pose"][4 * r + 3] for r in range(3)]
            assert abs(d[0] - east) < 1e-6 and abs(d[1] - north) < 1e-6 and abs(d[2]) < 1e-6, (mode, qa["index"], d)
    summary.append(f"{mode} {a['summary']['successes']}/{a['summary']['queries']}")
lines = {w: [json.loads(l) for l in open(f"{t}/{w}.localize.jsonl")] for w in ("local", "utm")}
assert len(lines["local"]) == len(lines["utm"]) == 31
identical, worst = 0, 0.0
for a, b in zip(lines["local"], lines["utm"]):
    assert a["status"] == b["status"], a["frame"]
    diff = max(abs(x - y) for x, y in zip(a["pose_map_local"], b["pose_map_local"]))
    worst = max(worst, diff)
    identical += a["pose_map_local"] == b["pose_map_local"]
    for r in range(3):
        assert abs(b["pose"][4 * r + 3] - b["pose_map_local"][4 * r + 3] - ut[r]) < 1e-6
assert worst < 1e-6, worst
print(f"geo ok: origin {lo} -> {ut}; successes {', '.join(summary)} in both; "
      f"map-local poses bit-identical for {identical} of {len(lines['local'])} scans (worst difference {worst:g} m)")
PY
echo "1 passed, 0 failed"
