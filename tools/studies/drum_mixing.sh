#!/usr/bin/env bash
# drum_mixing.sh — the particles' own mixing of C on the 2D drums (issue 57 item 1), one device call:
# each drum is developed to T_DEV s (a checkpoint), then restarted twice for a window of NSNAP
# snapshots SNAP_DT apart, once as the scene runs (Fickian shifting) and once with Flow:shifting off
# (the shifting's share), and each window (NSNAP snapshots after T_DEV) is measured by tools/analysis/drum_mixing.py
# (D_num against chi_D gdot d_avg^2, per class of shear rate). The snapshots are deleted after each
# measurement (at fit radii 2h and 3h); the JSONs and logs end in $OUT/drum_mixing_res.tgz.
#
#   OUT=DIR SPHSEG=BIN [BACKEND=gpu] [DRUMS="EV EN"] [DRS="0.001 0.0005 0.00025"] bash tools/studies/drum_mixing.sh
#   python3 -m tools.analysis.drum_mixing table res/*.json --csv docs/data/drum/drum_mixing.csv
#   python3 -m tools.analysis.drum_mixing chart --csv docs/data/drum/drum_mixing.csv --png docs/data/drum/drum_mixing.png
#
# The flow is seg_refine's (the scenes' flow at E 10 kPa, chi 0.2, the predictor-corrector; the
# scenes' Segregation), so the numbers sit beside docs/seg_refine.md's. At dr 0.25 mm on one H200
# (double) developing the EN drum to 4 s takes about a minute. With TINY=1 it is the local check:
# dr 2 mm, developed to 0.3 s, on the CPU.
set -u
cd "$(dirname "$0")/../.."
SPHSEG=${SPHSEG:-build/sphseg}
OUT=${OUT:-out/drum_mixing}
BACKEND=${BACKEND:-gpu}
PY=${PY:-python3}
DRUMS=${DRUMS:-EV EN}
DRS=${DRS:-0.001 0.0005 0.00025}
T_DEV=${T_DEV:-4}
SNAP_DT=${SNAP_DT:-0.01}
NSNAP=${NSNAP:-20}
LAGS=${LAGS:-1 2 4 8 12 16}  # in snapshot intervals: 10 to 160 ms, gdot tau up to 2.5 in the layer
FIT_FROM=${FIT_FROM:-4}         # the slopes from 40 ms: past the ballistic start (M grows as tau^2 below ~20 ms)
RADII=${RADII:-2 3}  # the fit's radii, in h: what counts as the continuum's motion
VARS=${VARS:-shift noshift}     # noshift: the same window with Flow:shifting off (the shifting's share)
# PERIODIC3D=1: the drum as a 3D container periodic along z over 24 dr, no end walls (as
# tools/studies/periodic_drum.py builds it; EV only), labelled EV3D; the tool reads its in-plane mixing
PERIODIC3D=${PERIODIC3D:-0}
STRIDE=${STRIDE:-1}             # time origins every STRIDE snapshots (2 halves the 3D analysis's time)
if [ "${TINY:-0}" = 1 ]; then DRS="0.002"; T_DEV=0.3; BACKEND=cpu; SNAP_DT=0.005; NSNAP=9; LAGS="1 2 4 8"; FIT_FROM=2; fi
FLOW=(-P Material:E=1e4 -P Run:cfl_flow=0.2 -P Output:diag_dt=0.5 -P Run:progress_s=60)
T_END=$($PY -c "print(round($T_DEV + $NSNAP * $SNAP_DT, 9))")  # the restart writes none at T_DEV: NSNAP after it
mkdir -p "$OUT/res" "$OUT/runs"
T0=$(date +%s)
for drum in $DRUMS; do
    for dr in $DRS; do
        GEO=(); tag=$drum
        if [ "$PERIODIC3D" = 1 ]; then
            tag=${drum}3D
            H=$($PY -c "print('%.4g' % ((2 * 0.42 - 1) * 0.035))")
            GEO=(-P Geometry:type=container -P Geometry:dim=3 -P "Geometry:depth=$($PY -c "print('%.6g' % (24 * $dr))")"
                 -P Geometry:periodic=z
                 -P "Container:walls=[{name: drum, shape: cylinder, centre: [0, 0], radius: 0.035, motion: turning, rpm: 5, direction: clockwise}]"
                 -P "Container:regions=[{shape: fill, level: $H, C: 0.5}]")
        fi
        lab=${tag}_dr$($PY -c "print('%g' % ($dr * 1e3))")
        dev="$OUT/runs/${lab}_dev"
        "$SPHSEG" "inputs/drum_2d_$drum.yml" --backend "$BACKEND" -o "$dev" "${FLOW[@]}" ${GEO[@]+"${GEO[@]}"} -P "Geometry:dr=$dr" \
            -P "Run:t_end=$T_DEV" -P "Output:dt=$T_DEV" -P "Output:checkpoint_dt=$T_DEV" > "$dev.log" 2>&1 ||
            { echo "$lab: developing failed (rc $?)"; tail -5 "$dev.log"; continue; }
        for var in $VARS; do
            extra=(); [ $var = noshift ] && extra=(-P Flow:shifting=off)
            w="$OUT/runs/${tag}_${var}_dr$($PY -c "print('%g' % ($dr * 1e3))")"
            "$SPHSEG" "inputs/drum_2d_$drum.yml" --backend "$BACKEND" -o "$w" "${FLOW[@]}" ${GEO[@]+"${GEO[@]}"} -P "Geometry:dr=$dr" \
                -P "Run:t_end=$T_END" -P "Output:dt=$SNAP_DT" -P "Output:checkpoint_dt=0" ${extra[@]+"${extra[@]}"} \
                --restart "$dev/checkpoint.h5" > "$w.log" 2>&1 || { echo "$w: window failed (rc $?)"; tail -5 "$w.log"; continue; }
            (   # measured beside the next runs (the device's cores are idle while the GPU runs)
                for rad in $RADII; do
                    r=$(basename "$w"); [ "$rad" = 2 ] || r=${r}_r$rad
                    $PY -m tools.analysis.drum_mixing "$w" --radius "$rad" --lags $LAGS --fit-from "$FIT_FROM" --stride "$STRIDE" --label "${tag}_${var}" \
                        --json "$OUT/res/$r.json" > "$OUT/res/$r.txt" 2>&1 || echo "$w: analysis failed" >> "$OUT/res/$r.txt"
                done
                rm -f "$w"/snapshot_*.h5
            ) &
        done
        tail -n 3 "$dev.log" > "$OUT/res/${lab}_dev.log"
        rm -rf "$dev"
        echo "$lab run at $(( $(date +%s) - T0 )) s"
    done
done
wait
cat "$OUT"/res/*.txt
tar czf "$OUT/drum_mixing_res.tgz" -C "$OUT" res && rm -rf "$OUT/runs"
echo "all done at $(( $(date +%s) - T0 )) s"
