#!/usr/bin/env bash
# Measures again the benchmark figures the book quotes, with the commands the book names, and prints each with the
# date, the machine's load and the command (the book's Measurements chapter, docs/src/measurements/, holds them):
# `bash docs/measure.sh` runs all of them (about an hour: run it on a
# quiet machine), `bash docs/measure.sh sweep ipc` the ones named. Paste what it prints beside the table it
# refreshes; the tables' own "command" columns are these commands.
#
#   model       silrig bench (plant derivative, RK4 step, closed-loop tick)         measurements/plants-controllers.md
#   timer       silrig timer-baseline (the OS floor)                                measurements/timing.md
#   ipc         silrig bench ipc (ping-pong ceilings, lockstep against them)        measurements/timing.md
#   realtime    silrig run --duration-s 30, 3 runs (wake-up lateness vs the floor)  measurements/timing.md
#   lockstep    20,000-tick lockstep runs, 3 runs: cycles/s, CPU per tick           measurements/recording.md
#   controllers lockstep 300 s: ours, the C and the Python PID, paired              measurements/plants-controllers.md
#   sweep       1,000-case sweep, --jobs 2 against --jobs 1, 7 pairs               measurements/campaigns.md
#   rigsweep    40 cases of the Python PID through the rig, --jobs 1 and 2         measurements/campaigns.md
#   fmu         silrig bench fmu on the exported F-16                             measurements/plants-controllers.md
#   sizes       the default run's files and report.html                          measurements/recording.md
#   check       silrig check --repeat 20 (the flake benchmark; about 20 minutes)  measurements/campaigns.md
#   peers       against FMPy and JSBSim, $PEERS_PAIRS pairs each (default 5), campaigns of $PEERS_CASES cases
#               (default 100) (examples/peers)                                   measurements/peers.md
set -euo pipefail
cd "$(dirname "$0")/.."
cargo build --release -q
export PATH="$PWD/target/release:$PATH"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
all=(model timer ipc realtime lockstep controllers sweep rigsweep fmu sizes check peers)
wanted=("$@")
[ ${#wanted[@]} -eq 0 ] && wanted=("${all[@]}")

header() {
  echo
  echo "== $1: $(date -u '+%Y-%m-%d %H:%M UTC'), $(nproc) CPUs, load average $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "   command: $2"
}
# The median, minimum and maximum of the numbers on stdin.
stats() { python3 -c 'import sys,statistics as s; v=[float(x) for x in sys.stdin.read().split()]; print(f"median {s.median(v):.4g} (min {min(v):.4g} .. max {max(v):.4g}, {len(v)} runs)")'; }
# Pairs "A B" on stdin (taken in turn, A B A B ...): each one's median, and the ratio A/B pair by pair.
pairs() { python3 -c 'import sys,statistics as s; p=[tuple(map(float,l.split())) for l in sys.stdin if l.strip()]; r=[a/b for a,b in p]; m=lambda v: f"{s.median(v):.4g} ({min(v):.4g} .. {max(v):.4g})"; print(f"A median {m([a for a,_ in p])}; B median {m([b for _,b in p])}; A/B per pair {m(r)}, {len(p)} pairs")'; }
# A figure of a report.json: report DIR EXPR, EXPR a Python expression on `r` (the report), `p99(name)` (a
# distribution's p99 in us, e.g. plant.wake_lateness) and `proc(role)` (a process's entry).
report() {
  python3 -c "
import json
r = json.load(open('$1/report.json'))
proc = lambda role: next(p for p in r['processes'] if p['process'] == role)
p99 = lambda name: next(l['summary']['p99_us'] for p in r['processes'] for l in p['latencies'] if l['name'] == name)
print($2)"
}
# Wall seconds of a command.
wall() { local t0 t1; t0=$(date +%s.%N); "$@" > /dev/null 2>&1 || true; t1=$(date +%s.%N); python3 -c "print(round($t1 - $t0, 3))"; }

for name in "${wanted[@]}"; do
  case $name in
    model) header model "silrig bench"; silrig bench ;;
    timer) header timer "silrig timer-baseline"; silrig timer-baseline ;;
    ipc) header ipc "silrig bench ipc"; silrig bench ipc ;;
    realtime)
      header realtime "silrig run --duration-s 30 (3 runs)"
      for k in 1 2 3; do
        silrig run --duration-s 30 --quiet --no-figures --out "$work/rt$k" > /dev/null
        report "$work/rt$k" "'plant wake p99 %.1f us, OS floor p99 %.1f us, sense-to-actuate p99 %.1f us' % (p99('plant.wake_lateness'), r['timer_baseline']['lateness']['p99_us'], p99('plant.sense_to_actuate'))"
      done ;;
    lockstep)
      header lockstep "silrig run --mode lockstep --duration-s 200 --no-baseline --no-figures --quiet (3 runs)"
      for k in 1 2 3; do
        silrig run --mode lockstep --duration-s 200 --no-baseline --no-figures --quiet --out "$work/ls$k" > /dev/null
        report "$work/ls$k" "'cycles/s %.0f; CPU us/tick: ' % r['cycles_per_s'] + ', '.join('%s %.1f' % (p, 1e6 * proc(p)['cpu_s'] / 20001) for p in ('plant', 'controller', 'logger'))"
      done ;;
    controllers)
      cc -std=c11 -O2 -I examples/c examples/c/pid_attitude.c -L target/release -lsilrig_client \
        -Wl,-rpath,"$PWD/target/release" -lm -o "$work/pid_attitude"
      base="silrig run --mode lockstep --duration-s 300 --no-baseline --quiet --no-figures"
      for who in ours "c:$work/pid_attitude" "python:python3 examples/python/pid_attitude.py"; do
        cmd=${who#*:}
        header "controllers ($who)" "$base${cmd:+ --controller-cmd \"$cmd\"} (5 runs, wall s)"
        for k in 1 2 3 4 5; do
          if [ "$who" = ours ]; then wall $base --out "$work/c-ours-$k"
          else wall $base --controller-cmd "$cmd" --out "$work/c-${who%%:*}-$k"; fi
        done | stats
      done ;;
    sweep)
      for jobs in 2 1; do
        header "sweep --jobs $jobs" "silrig sweep configs/sweep-robust.toml --runs 1000 --jobs $jobs (7 runs, wall s)"
        for k in 1 2 3 4 5 6 7; do wall silrig sweep configs/sweep-robust.toml --runs 1000 --jobs $jobs --out "$work/sw$jobs-$k"; done | stats
      done ;;
    rigsweep)
      for jobs in 1 2; do
        header "rigsweep --jobs $jobs" "silrig sweep configs/sweep-robust.toml --runs 40 --jobs $jobs --controller-cmd \"python3 examples/python/pid_attitude.py\" (3 runs, wall s)"
        for k in 1 2 3; do wall silrig sweep configs/sweep-robust.toml --runs 40 --jobs $jobs --controller-cmd "python3 examples/python/pid_attitude.py" --out "$work/rs$jobs-$k"; done | stats
      done ;;
    fmu)
      header fmu "silrig export-fmu --out f16.fmu && silrig bench fmu f16.fmu"
      silrig export-fmu --out "$work/f16.fmu" > /dev/null
      silrig bench fmu "$work/f16.fmu" ;;
    sizes)
      header sizes "silrig run --no-baseline (the default 10 s run)"
      silrig run --no-baseline --quiet --out "$work/size" > /dev/null
      (cd "$work/size" && ls -l recording.mcap trace.csv timing.csv report.html | awk '{printf "%s %.2f MB\n", $9, $5 / 1e6}') ;;
    check)
      header check "silrig check --repeat 20"
      silrig check --repeat 20 --out "$work/repeat" | tail -n 60 ;;
    peers)
      # Set up (not timed): the C PID, the PID FMU, the two scenarios' F-16 FMUs, the trace FMPy replays, the
      # cases FMPy flies. The Python is target/test-venv's (fmpy, jsbsim), or $PEERS_PYTHON.
      py=${PEERS_PYTHON:-target/test-venv/bin/python3}
      n=${PEERS_PAIRS:-5}
      cases=${PEERS_CASES:-100}
      cc -std=c11 -O2 -I examples/c examples/c/pid_attitude.c -L target/release -lsilrig_client \
        -Wl,-rpath,"$PWD/target/release" -lm -o "$work/pid_attitude"
      PYTHON=$py sh examples/fmu/build.sh examples/fmu/pid "$work/pid.fmu" > /dev/null
      silrig export-fmu --out "$work/f16-100s.fmu" examples/peers/f16-100s.toml > /dev/null
      silrig export-fmu --out "$work/campaign.fmu" examples/peers/pid-campaign.toml > /dev/null
      silrig sim --plant-fmu "$work/f16-100s.fmu" --out "$work/sim" examples/peers/f16-100s.toml > /dev/null
      sweep="silrig sweep examples/peers/pid-campaign.toml --runs $cases --jobs 1 --controller-cmd $work/pid_attitude"
      $sweep --out "$work/cases" > /dev/null 2>&1
      header "peers: sim against simulate_fmu" "A: silrig sim --plant-fmu f16-100s.fmu examples/peers/f16-100s.toml; B: $py examples/peers/fmpy_f16.py simulate f16-100s.fmu TRACE OUT.csv ($n pairs, wall s)"
      for k in $(seq "$n"); do
        echo "$(wall silrig sim --plant-fmu "$work/f16-100s.fmu" --out "$work/sim$k" examples/peers/f16-100s.toml)" \
          "$(wall "$py" examples/peers/fmpy_f16.py simulate "$work/f16-100s.fmu" "$work/sim/trace.csv" "$work/fmpy$k.csv")"
      done | pairs
      "$py" examples/peers/fmpy_f16.py compare "$work/sim/trace.csv" "$work/fmpy1.csv"
      header "peers: F-16 step against JSBSim's" "A: silrig bench (plant RK4 step); B: $py examples/peers/jsbsim_f16.py bench ($n pairs, ns a step)"
      for k in $(seq "$n"); do
        echo "$(silrig bench | awk '/plant RK4 step/ {print $8}') $("$py" examples/peers/jsbsim_f16.py bench | awk '/JSBSim f16 step/ {print $8}')"
      done | pairs
      header "peers: campaign of $cases cases" "A: $sweep; B: $py examples/peers/fmpy_campaign.py campaign.fmu pid.fmu cases.csv OUT.csv ($n pairs, wall s)"
      for k in $(seq "$n"); do
        echo "$(wall $sweep --out "$work/sweep$k")" \
          "$(wall "$py" examples/peers/fmpy_campaign.py "$work/campaign.fmu" "$work/pid.fmu" "$work/cases/cases.csv" "$work/fc$k.csv")"
      done | pairs ;;
    *) echo "unknown benchmark $name; one of: ${all[*]}" >&2; exit 2 ;;
  esac
done
