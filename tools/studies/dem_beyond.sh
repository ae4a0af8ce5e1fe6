#!/usr/bin/env bash
# tools/studies/dem_beyond.sh OUT [BIN] — the DEM "beyond the paper" studies
# of docs/dem.md (issue 58): hindered settling at eps 0.6, 0.7, 0.8, 0.9
# (tests/validate_dem_hindered.py --full) with four numerical variants at
# eps 0.8 (c_s 10 m/s; the fluid at dr = period / 17 with h kept; h 1.2 dr;
# DEM:kn 1000 N/m) and c_s 10 m/s at eps 0.6, and the packed bed
# (inputs/dem_bed.yml as it stands) with three variants (c_s 10 m/s; the
# block released on the base; DEM:kn 300 N/m). Fourteen runs at once,
# OMP_NUM_THREADS each (default 1, sized for a 16-core host); each run's check
# goes to OUT/NAME.log, then the chart and the tables:
#
#   bash tools/studies/dem_beyond.sh /tmp/dem_beyond build/sphseg
#   (then docs/data/dem/dem_beyond.png and the tables in OUT/tables.md)
set -u
out=${1:?usage: $0 OUT [BIN]}
bin=$(realpath "${2:-build/sphseg}")
cd "$(dirname "$0")/../.."
PY=${PYTHON:-/usr/bin/python3}
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1}
mkdir -p "$out"
hs() { # NAME EPS [--extra K=V ...] [--tag T]
    local name=$1 eps=$2; shift 2
    { /usr/bin/time -f "wall %e s, cpu %U s" "$PY" -m tests.validate_dem_hindered --full --eps "$eps" \
        --sphseg "$bin" --work "$out" "$@"; } >"$out/$name.log" 2>&1 &
}
bed() { # NAME [-P K=V ...]
    local name=$1; shift
    { /usr/bin/time -f "wall %e s, cpu %U s" "$bin" inputs/dem_bed.yml -o "$out/$name" --overwrite \
        -P Run:progress_s=1e9 "$@" >"$out/$name.run.log" 2>&1 &&
        "$PY" -m tests.validate_dem_bed --full --analyse "$out/$name"; } >"$out/$name.log" 2>&1 &
}
for e in 0.6 0.7 0.8 0.9; do hs "hs_$e" "$e"; done
hs hs_0.8_cs10 0.8 --extra Material:E=120000 --tag _cs10
# dr = period / 17 = 3.89 mm, h_factor 1.5 * 17 / 13: the same h (7.63 mm), 1.3 times finer; the water stands
# 28 rows deep (10.9 cm, 1.7 cm over the block: the fill holds whole rows)
hs hs_0.8_dr17 0.8 --extra Geometry:dr=0.00389148348 --extra Geometry:h_factor=1.96153846 --tag _dr17
hs hs_0.8_h1.2 0.8 --extra Geometry:h_factor=1.2 --tag _h1.2
hs hs_0.8_kn1000 0.8 --extra DEM:kn=1000 --tag _kn1000
hs hs_0.6_cs10 0.6 --extra Material:E=120000 --tag _cs10
bed bed
bed bed_cs10 -P Material:E=120000
bed bed_onbase -P "DEM:block_origin=[0.002665, 0.002, 0.002665]"
bed bed_kn300 -P DEM:kn=300
wait
{
    "$PY" -m tools.studies.dem_beyond_chart --hindered 0.6="$out/eps0.6_full" 0.7="$out/eps0.7_full" \
        0.8="$out/eps0.8_full" 0.9="$out/eps0.9_full" --bed "$out/bed" --png docs/data/dem/dem_beyond.png
    for v in 0.8_cs10 0.8_dr17 0.8_h1.2 0.8_kn1000 0.6_cs10; do echo; echo "eps $v:"; tail -n 2 "$out/hs_$v.log"; done
    for v in bed_cs10 bed_onbase bed_kn300; do echo; echo "$v:"; cat "$out/$v.log"; done
} >"$out/tables.md" 2>&1
cat "$out/tables.md"
