#!/usr/bin/env bash
# Draws what bench/dds_bridge.sh wrote into OUT_DIR: the 1 KiB round trips' CDFs (raw
# Cyclone DDS and afhub through two bridges: asleep, with idle CPUs polling, and with
# the bridges polling) and, second by second, the age of the states a DDS reader
# received from a bridge exporting its bodies at 1 kHz, normally and under overload.
# Needs gnuplot.
#   bench/dds_bridge_plot.sh OUT_DIR PNG
set -euo pipefail
out=$1
png=$2
command -v gnuplot >/dev/null || { echo "dds_bridge_plot.sh: needs gnuplot (apt-get install gnuplot-nox)" >&2; exit 1; }
bodies=$(grep -o '^[0-9]* bodies at 1 kHz' "$out/summary.txt" | cut -d' ' -f1)
data=$(mktemp -d)
trap 'rm -rf "$data"' EXIT
# cdf FILE: "microseconds fraction" per sorted round trip.
cdf() { sort -n "$1" | awk '{v[NR] = $1} END {for (i = 1; i <= NR; i++) print v[i] / 1e3, i / NR}'; }
cdf "$out/raw_rtt_ns.txt" >"$data/raw"
cdf "$out/bridge_rtt_ns.txt" >"$data/bridge"
cdf "$out/raw_rtt_ns_wake.txt" >"$data/raw_wake"
cdf "$out/bridge_rtt_ns_wake.txt" >"$data/bridge_wake"
cdf "$out/raw_rtt_ns_spin.txt" >"$data/raw_spin"
cdf "$out/bridge_rtt_ns_spin.txt" >"$data/bridge_spin"
for name in normal overload; do
  jq -r '"\(.t_s) \(.age_p50_us / 1000) \(.age_max_us / 1000) \(.states)"' "$out/load_$name.jsonl" >"$data/$name"
done
title=$(head -1 "$out/summary.txt")
gnuplot <<GNUPLOT
set terminal pngcairo size 1200,480 font "sans,10"
set output "$png"
set multiplot layout 1,2 title "$title"
set title "1 KiB round trip between two network namespaces"
set xlabel "round trip (us)"
set ylabel "fraction of round trips"
set logscale x
set key bottom right
set grid
plot "$data/raw" using 1:2 with lines lw 2 title "Cyclone DDS alone", \
     "$data/bridge" using 1:2 with lines lw 2 title "afhub -> bridge -> DDS -> bridge -> afhub", \
     "$data/raw_wake" using 1:2 with lines lw 2 dt 3 title "Cyclone DDS alone, idle CPUs polling", \
     "$data/bridge_wake" using 1:2 with lines lw 2 dt 3 title "afhub via two bridges --cpu-wake-latency 0", \
     "$data/raw_spin" using 1:2 with lines lw 2 dt 2 title "Cyclone DDS alone, beside polling bridges", \
     "$data/bridge_spin" using 1:2 with lines lw 2 dt 2 title "afhub via two bridges --spin"
unset logscale x
set title "$bodies bodies at 1 kHz exported: age of the states a DDS reader gets"
set xlabel "second of the window"
set ylabel "age at the reader (ms)"
set logscale y
set key top left
plot "$data/normal" using 1:2 with linespoints lw 2 title "normal: p50", \
     "$data/normal" using 1:3 with linespoints dt 2 title "normal: max", \
     "$data/overload" using 1:2 with linespoints lw 2 title "overload (20 Mbit/s, reliable, slow reader): p50", \
     "$data/overload" using 1:3 with linespoints dt 2 title "overload: max"
unset multiplot
GNUPLOT
echo "wrote $png"
