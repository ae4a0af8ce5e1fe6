#!/bin/bash
# The chart and table of README.md, from this folder's drum_analysis outputs (development machine).
D=docs/data/stabilization/filter_interval
/usr/bin/python3 -m tools.studies.filter_interval_chart --png $D/filter_interval.png \
 --run "EV dr 0.5 mm: cfl 0.2, N 30;6;$D/c02.ana;2.5;4" \
 --run "EV dr 0.5 mm: cfl 0.1, N 30;3;$D/c01.ana;2.5;4" \
 --run "EV dr 0.5 mm: cfl 0.05, N 30;1.5;$D/c005.ana;2.5;4" \
 --run "EV dr 0.5 mm: cfl 0.05, N 120;6;$D/c005s120.ana;2.5;4" \
 --run "EV dr 0.5 mm: cfl 0.1, N 60;6;$D/c01s60.ana;2.5;4" \
 --run "EV dr 0.5 mm: cfl 0.2, off;0;$D/r05s0.ana;2.5;4" \
 --run "EV dr 0.25 mm: cfl 0.1, N 30;3;$D/q01.ana;2.5;4" \
 --run "EV dr 0.25 mm: cfl 0.1, N 60;6;$D/q01s60.ana;2.5;4" \
 --run "EN dr 0.5 mm: cfl 0.1, N 30;3;$D/n01.ana;2.5;4" \
 --run "EN dr 0.5 mm: cfl 0.1, N 60;6;$D/n01s60.ana;2.5;4"
