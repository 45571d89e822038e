#!/usr/bin/env bash
# CLI contract test (host builds): usage errors exit 2 with a message, runtime errors exit 1, and the
# documented pipeline simulate -> build-map -> evaluate --json works on the tiny world with the
# expected success counts (ground truth known) and a JSON file holding the documented fields (per query
# confidence and the decision rule's "answered"; per mode reliability bins, ECE, the rule's counts); poses
# come in the map's frame and the map-local one, apart by the map origin.
set -u
gsf=$1
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
expect() {  # expect CODE PATTERN -- command...
  local code=$1 pat=$2; shift 3
  out=$("$@" 2>&1); rc=$?
  [ "$rc" = "$code" ] || fail "'$*' exited $rc, expected $code: $out"
  echo "$out" | grep -q -- "$pat" || fail "'$*' output lacks '$pat': $out"
}
expect 2 "usage: gsf" -- "$gsf"
expect 2 "unknown command" -- "$gsf" frobnicate
expect 0 "evaluate" -- "$gsf" --help
expect 0 "--dataset" -- "$gsf" evaluate --help
expect 2 "unknown option '--bogus'" -- "$gsf" evaluate --bogus 1
expect 2 "missing required option '--map'" -- "$gsf" evaluate --dataset x
expect 2 "bad --mode" -- "$gsf" evaluate --map m --dataset d --mode teleport
expect 2 "expects an integer" -- "$gsf" evaluate --map m --dataset d --limit ten
expect 2 "min-confidence must be in" -- "$gsf" evaluate --map m --dataset d --min-confidence 1.01
expect 2 "min-confidence must be in" -- "$gsf" evaluate --map m --dataset d --min-confidence -0.1
expect 2 "unknown config name" -- "$gsf" build-map --dataset d --out m --set match.nonsense=1
expect 2 "gsf.tau must be (0, 1000]" -- "$gsf" build-map --dataset d --out m --set gsf.tau=0
expect 2 "must be <= hypotheses.shift_bin" -- "$gsf" build-map --dataset d --out m --set hypotheses.tls_threshold=3
expect 0 "gsf.tau = 0.1 (default 0.2)" -- "$gsf" params --set gsf.tau=0.1
expect 2 "given twice" -- "$gsf" params --set gsf.tau=0.1 --set gsf.tau=0.2
expect 0 "## User-facing (25)" -- "$gsf" params --markdown
# Simulated network errors on the labels read (build-map, evaluate, localize): rates in 0..1, seed >= 0.
expect 2 "label-noise must be a number in 0..1" -- "$gsf" evaluate --map m --dataset d --label-noise 1.5
expect 2 "object-confusion must be a number in 0..1" -- "$gsf" build-map --dataset d --out m --object-confusion -0.1
expect 2 "thin-miss must be a number in 0..1" -- "$gsf" localize --map m --dataset d --thin-miss x
expect 2 "noise-seed must be a whole number" -- "$gsf" evaluate --map m --dataset d --noise-seed -3
expect 1 "cannot open map file" -- "$gsf" evaluate --map "$tmp/none.gsfmap" --dataset "$tmp"
# Vehicle modes (docs/vehicle-modes.md): priors and tracking options.
expect 2 "prior must be x,y,radius" -- "$gsf" localize --map m --dataset d --prior 1,2
expect 2 "prior: invalid" -- "$gsf" localize --map m --dataset d --prior 1,2,-5
expect 2 "need --prior-sigma" -- "$gsf" evaluate --map m --dataset d --prior-bias 100
expect 2 "need --prior-sigma" -- "$gsf" evaluate --map m --dataset d --prior-heading-tolerance 30
expect 2 "prior-heading-tolerance in" -- "$gsf" evaluate --map m --dataset d --prior-sigma 5 \
  --prior-heading-tolerance 200
expect 2 "one-shot-too needs --prior-sigma" -- "$gsf" evaluate --map m --dataset d --one-shot-too
expect 2 "repeat must be 1..100" -- "$gsf" evaluate --map m --dataset d --repeat 0
expect 2 "for the per-query modes" -- "$gsf" evaluate --map m --dataset d --mode track --repeat 2
expect 2 "odometry-noise must be in" -- "$gsf" evaluate --map m --dataset d --mode track --odometry-noise 2
expect 2 "prediction-offset must be in" -- "$gsf" evaluate --map m --dataset d --mode track --prediction-offset -1
expect 2 "sequence-window must be 1..4" -- "$gsf" evaluate --map m --dataset d --sequence-window 5
expect 1 "cannot open sequence" -- "$gsf" build-map --dataset "$tmp/nothing" --out "$tmp/m.gsfmap"
expect 2 "block-tiles must be a count" -- "$gsf" build-map --dataset d --out m --block-tiles -1
printf 'not a map' > "$tmp/bad.gsfmap"
expect 1 "not a valid map" -- "$gsf" inspect --map "$tmp/bad.gsfmap"

"$gsf" simulate --preset tiny --out "$tmp/ds" --stretches 2 --stretch-scans 10 --quiet >/dev/null || fail "simulate"
built=$("$gsf" build-map --dataset "$tmp/ds" --sequence 00 --out "$tmp/map.gsfmap" --quiet) || fail "build-map"
echo "$built" | grep -Eq "peak RSS [1-9][0-9]* MB" || fail "build-map summary lacks its peak RSS: $built"
echo "$built" | grep -q "origin 0.000, -2.000, 2.000 m in frame 'local'" || fail "build-map summary lacks the origin: $built"
# Block by block (the default, no spill file) or in one pass with the spill file: the same map bytes.
echo "$built" | grep -q "no spill file" || fail "build-map did not build in blocks: $built"
"$gsf" build-map --dataset "$tmp/ds" --sequence 00 --out "$tmp/map1.gsfmap" --quiet --tile-size 16 --block-tiles 0 \
  --resident-tiles 3 | grep -q "spill file peak" || fail "build-map --block-tiles 0"
cmp -s "$tmp/map.gsfmap" "$tmp/map1.gsfmap" || fail "the one-pass map differs from the blocked one"
"$gsf" inspect --map "$tmp/map.gsfmap" --json > "$tmp/inspect.json" || fail "inspect"
# A regular file is memory-mapped; a pipe cannot be, so it is read into memory, and loads the same.
"$gsf" inspect --map "$tmp/map.gsfmap" | grep -q "memory-mapped (used in place)" || fail "map file not mapped"
"$gsf" inspect --map <(cat "$tmp/map.gsfmap") | grep -q "read into memory" || fail "map through a pipe"
"$gsf" evaluate --map "$tmp/map.gsfmap" --dataset "$tmp/ds" --sequence 01 --json "$tmp/out.json" --mode all \
  --svg "$tmp/svg" --quiet >/dev/null || fail "evaluate"
"$gsf" evaluate --map "$tmp/map.gsfmap" --dataset "$tmp/ds" --sequence 01 --json "$tmp/all.json" --mode gsf,scan-context \
  --min-confidence 0 --limit 12 --quiet >/dev/null || fail "evaluate --min-confidence 0"
"$gsf" localize --map "$tmp/map.gsfmap" --dataset "$tmp/ds" --sequence 01 --frame 3 > "$tmp/one.json" || fail "localize"
"$gsf" evaluate --map "$tmp/map.gsfmap" --dataset "$tmp/ds" --sequence 01 --json "$tmp/noisy.json" --mode gsf --limit 2 \
  --label-noise 0.1 --object-confusion 0.15 --noise-seed 7 --quiet >/dev/null || fail "evaluate --label-noise"
"$gsf" evaluate --map "$tmp/map.gsfmap" --dataset "$tmp/ds" --mode track --json "$tmp/track.json" --quiet \
  >/dev/null || fail "evaluate --mode track"
"$gsf" evaluate --map "$tmp/map.gsfmap" --dataset "$tmp/ds" --mode track --prediction-offset 8 \
  --json "$tmp/track_off.json" --quiet >/dev/null || fail "evaluate --mode track --prediction-offset"
"$gsf" evaluate --map "$tmp/map.gsfmap" --dataset "$tmp/ds" --mode drive --json "$tmp/drive.json" --quiet \
  >/dev/null || fail "evaluate --mode drive"
"$gsf" evaluate --map "$tmp/map.gsfmap" --dataset "$tmp/ds" --sequence-window 3 --json "$tmp/window.json" --quiet \
  >/dev/null || fail "evaluate --sequence-window"
"$gsf" evaluate --map "$tmp/map.gsfmap" --dataset "$tmp/ds" --sequence 01 --json "$tmp/prior.json" --mode gsf --limit 6 \
  --prior-sigma 5 --prior-radius 20 --quiet >/dev/null || fail "evaluate --prior-sigma"
"$gsf" evaluate --map "$tmp/map.gsfmap" --dataset "$tmp/ds" --sequence 01 --json "$tmp/prior_both.json" --mode gsf \
  --limit 6 --prior-sigma 5 --prior-radius 20 --one-shot-too --repeat 2 --quiet >/dev/null ||
  fail "evaluate --one-shot-too --repeat"
"$gsf" evaluate --map "$tmp/map.gsfmap" --dataset "$tmp/ds" --sequence 01 --json "$tmp/prior_heading.json" --mode gsf \
  --limit 6 --prior-sigma 5 --prior-radius 20 --prior-heading-tolerance 30 --quiet >/dev/null ||
  fail "evaluate --prior-heading-tolerance"
xy=$(python3 -c "import json,sys; p=json.loads(open(sys.argv[1]).readline())['pose']; print(f'{p[3]+3},{p[7]-4}')" \
  "$tmp/one.json") || fail "one.json"
"$gsf" localize --map "$tmp/map.gsfmap" --dataset "$tmp/ds" --sequence 01 --frame 3 --prior "$xy,20" \
  > "$tmp/one_prior.json" || fail "localize --prior"
python3 - "$tmp" <<'PY' || exit 1
import json, sys, os
t = sys.argv[1]
r = json.load(open(f"{t}/out.json"))
for k in ["map", "map_bytes", "map_bytes_per_km", "road_length_m", "modes"]:
    assert k in r, k
modes = r["modes"]
assert set(modes) == {"instance", "gsf", "gsf+refine", "scan-context"}, modes.keys()
for name, m in modes.items():
    s = m["summary"]
    for k in ["success_rate", "zone_success_rate", "ate_m", "are_deg", "median_ms", "p95_ms", "workspace_bytes",
              "precision_curve", "median_stage_ms", "time_ratio_to_instance"]:
        assert k in s, (name, k)
    assert len(m["queries"]) == s["queries"] == 31, (name, len(m["queries"]))
    for q in m["queries"]:
        for k in ["index", "frame", "success", "translation_error_m", "rotation_error_deg", "time_ms", "status"]:
            assert k in q, (name, k)
g, i = modes["gsf"]["summary"], modes["instance"]["summary"]
# The decision rule (answered = status Ok and confident) and the confidence's calibration.
for name, m in modes.items():
    s, qs = m["summary"], m["queries"]
    for q in qs:
        assert 0 <= q["confidence"] <= 1 and isinstance(q["answered"], bool), (name, q["confidence"])
        assert not q["answered"] or q["status"] == "Ok", (name, q["index"])
        assert "success" in q and (name == "scan-context" or "confidence_evidence" in q["diagnostics"]), name
    rel = s["reliability"]
    assert len(rel) == 10 and rel[0]["lo"] == 0 and rel[-1]["hi"] == 1, rel
    assert sum(b["count"] for b in rel) == s["queries"], (name, rel)
    assert 0 <= s["ece"] <= 1 and 0 <= s["brier"] <= 1, (name, s["ece"], s["brier"])
    answered = [q for q in qs if q["answered"]]
    assert s["answered"] == len(answered) and abs(s["answered_at_rule"] - len(answered) / len(qs)) < 1e-6, name
    assert s["wrong_at_rule"] == sum(not q["success"] for q in answered), name
    assert s["declined_right"] == sum(q["success"] and not q["answered"] for q in qs), name
    assert abs(s["min_confidence"] - 0.9) < 1e-6, s["min_confidence"]  # the library's default
every = json.load(open(f"{t}/all.json"))["modes"]
for name, m in every.items():  # --min-confidence 0: every query with a pose is answered
    assert m["summary"]["min_confidence"] == 0, m["summary"]["min_confidence"]
    assert all(q["answered"] == (q["status"] == "Ok") for q in m["queries"]), name
    assert m["summary"]["answered"] == m["summary"]["with_pose"] > 0, m["summary"]
# Known answers from the simulator's ground truth (tiny world, 31 queries, 6 in the zone).
assert g["zone_queries"] == 6, g["zone_queries"]
assert g["successes"] >= 20, g["successes"]
assert g["zone_success_rate"] >= 5 / 6, g["zone_success_rate"]
assert g["zone_success_rate"] >= i["zone_success_rate"], (g["zone_success_rate"], i["zone_success_rate"])
assert modes["gsf+refine"]["summary"]["ate_m"] < g["ate_m"]
assert json.load(open(f"{t}/inspect.json"))["instances"] > 50
# Several scans: every stretch scan once, each listing the scans combined (newest first, itself first).
w = json.load(open(f"{t}/window.json"))
assert w["sequence_window"] == 3 and w["summary"]["all"]["scans"] == len(w["scans"]) == 20, w["summary"]
for q in w["scans"]:
    assert q["window_ids"][0] == q["sequence_index"] and len(q["window_ids"]) <= 3, q
    assert q["combined"] == (len(q["window_ids"]) > 1), q
    assert not q["answered"] or q["status"] == "Ok", q
    assert 0.0 <= q["known_share"] <= 1.0 and 0.0 <= q["agreement"] <= 1.0, q  # the answer's, as measured
    assert not q["answered"] or q["known_share"] > 0.0, q  # never vouched for with no sample on the map
assert w["summary"]["all"]["confident_wrong"] == sum(q["answered"] and not q["success"] for q in w["scans"])
one = json.loads(open(f"{t}/one.json").read().splitlines()[0])
assert one["frame"] == 3 and len(one["pose"]) == 12
# Two frames: "pose" is the map's frame, "pose_map_local" relative to the map origin (same rotation).
ins = json.load(open(f"{t}/inspect.json"))
origin = ins["origin"]
assert r["map_origin"] == origin and r["map_frame"] == ins["frame"] == one["map_frame"], (r["map_origin"], origin)
for row in range(3):
    for c in range(3):
        assert one["pose"][4 * row + c] == one["pose_map_local"][4 * row + c]
    assert one["pose"][4 * row + 3] == one["pose_map_local"][4 * row + 3] + origin[row], row
answered = [q for q in modes["gsf"]["queries"] if q["status"] == "Ok"]
assert answered and all(len(q["pose"]) == 12 for q in answered)
assert "match_dropped" in one["diagnostics"] and "hypotheses" in one["diagnostics"], one.keys()
for f in ["map_trajectory.svg", "correspondences_instance.svg", "correspondences_gsf.svg", "reliability.svg"]:
    assert open(f"{t}/svg/{f}").read().startswith("<svg"), f
assert "ECE" in open(f"{t}/svg/reliability.svg").read()
# The label errors a run applied are in its JSON (all 0: ground-truth labels).
assert r["label_errors"] == {"label_noise": 0, "object_confusion": 0, "thin_miss": 0, "noise_seed": 1,
                             "label_space": "semantic-kitti"}, r["label_errors"]
noisy = json.load(open(f"{t}/noisy.json"))["label_errors"]
assert abs(noisy["label_noise"] - 0.1) < 1e-6 and abs(noisy["object_confusion"] - 0.15) < 1e-6, noisy
assert noisy["noise_seed"] == 7, noisy
# Tracking over the stretches of sequence 02 and a prior around the truth.
tr = json.load(open(f"{t}/track.json"))
ts = tr["summary"]
assert tr["mode"] == "track" and ts["scans"] == 20 == len(tr["scans"]), ts
assert ts["tracked"] > 0 and ts["confident_wrong"] == 0 and ts["tracked_precise"] >= ts["tracked"] - 1, ts
assert all(s["how"] in ("one-shot", "track", "recovery") for s in tr["scans"])
# Predictions knocked up to 8 m / 8 deg off: the offset is recorded, each attempt says how far its result
# moved from its prediction, and a result beyond the search's reach (3.75 m) is never vouched for.
off = json.load(open(f"{t}/track_off.json"))
assert off["prediction_offset"] == 8 and off["summary"]["confident_wrong"] == 0, off["summary"]
att = [s["track_attempt"] for s in off["scans"] if "track_attempt" in s]
assert att and all(a["from_prediction_m"] >= 0 for a in att), att
assert all(a["confidence"] == 0 for a in att if a["from_prediction_m"] > 3.75 + 1e-6), att
assert any(a["from_prediction_m"] > 0.5 for a in att), att
dr = json.load(open(f"{t}/drive.json"))
ds = dr["summary"]
assert dr["mode"] == "drive" and ds["scans"] == 20 == len(dr["scans"]), ds
assert ds["tracked"] > 0 and ds["confident_wrong"] == 0, ds
# The error along the true scan's axes is the translation error, split (the same vector, another frame);
# scans without a pose carry none.
for s in tr["scans"]:
    if s["status"] != "Ok":
        assert "error_in_scan_m" not in s, s
        continue
    e = s["error_in_scan_m"]
    assert len(e) == 3 and abs(sum(v * v for v in e) ** 0.5 - s["translation_error_m"]) < 1e-6 * max(
        1.0, s["translation_error_m"]), s
pr = json.load(open(f"{t}/prior.json"))
assert pr["prior"]["radius_m"] == 20 and pr["modes"]["gsf"]["summary"]["successes"] >= 5, pr["prior"]
ph = json.load(open(f"{t}/prior_heading.json"))  # a heading 30 deg wide keeps the true poses
assert ph["prior"]["heading_tolerance_deg"] == 30 and pr["prior"]["heading_tolerance_deg"] == 0, ph["prior"]
assert ph["modes"]["gsf"]["summary"]["successes"] >= 5, ph["modes"]["gsf"]["summary"]
# --one-shot-too: the prior's run answers as --prior-sigma alone, and its one-shot twin as --mode gsf does
# (out.json: the same scans without a prior); --repeat keeps the answers and only times again.
pb = json.load(open(f"{t}/prior_both.json"))["modes"]
assert set(pb) == {"gsf", "gsf-one-shot"}, set(pb)
for a, b in zip(pb["gsf"]["queries"], pr["modes"]["gsf"]["queries"]):
    assert a["pose"] == b["pose"] and a["confidence"] == b["confidence"], (a["index"], a["pose"], b["pose"])
for a, b in zip(pb["gsf-one-shot"]["queries"], r["modes"]["gsf"]["queries"]):
    assert a["pose"] == b["pose"] and a["confidence"] == b["confidence"], (a["index"], a["pose"], b["pose"])
assert not any(q["diagnostics"].get("prior_outside_matches") for q in pb["gsf-one-shot"]["queries"])
assert all(q["diagnostics"]["prior_outside_matches"] > 0 for q in pr["modes"]["gsf"]["queries"])
one_prior = json.loads(open(f"{t}/one_prior.json").read().splitlines()[0])
assert one_prior["status"] == "Ok" and one_prior["diagnostics"]["prior_outside_matches"] > 0, one_prior["status"]
assert max(abs(a - b) for a, b in zip(one_prior["pose"], one["pose"])) < 0.5
print("cli ok:", g["successes"], "GSF successes,", i["successes"], "instance-only")
PY
echo "1 passed, 0 failed"
