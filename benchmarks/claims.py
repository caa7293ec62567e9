#!/usr/bin/python3
"""The claims check: every speed figure the README and docs/ quote that a benchmark of this tree
can measure, measured again in one run and printed beside the figure as the docs state it.

The claimed values are read from the documents themselves (each claim is a pattern over one
document's text), so a figure edited in the docs is checked as edited, and a claim whose text is no
longer found is reported (`missing`), never skipped silently. The measurements come from the
project's Google Benchmark programs, run once each with `--benchmark_repetitions=R` so that every
figure has a spread (the smallest and the largest of the R repetitions) besides its median:

  vibro_bench          events/s of the exact engine, the store's share of the speed, the cost per
                       event with several contacts, the Lyapunov exponents' cost, proof, orbit and
                       continuation times, the basin's cells/s;
  vibro_loads_bench    loads/plain;
  vibro_startup_bench  a whole process's CPU over /bin/true.

Verdict per claim: `holds` when the claimed value (or range) and the measured [min, max], each
widened by the tolerance (default 10 %: the machine is shared), overlap; `faster` or `slower` when
the measurement lies wholly above or below (a rate above its claim is `faster`, a time below its
claim too). A range over scenes (the peers' ratios) must match the measured [min, max] at both
ends within the tolerance, else `differs`. The peers' figures are read from the CSV of the peers run,
docs/peers.csv (benchmarks/peers/run_all.py, about 25 minutes on a loaded machine): the quoted ranges
of ×CW (the peer's in-process call against a whole vibro process, at the peer's most accurate
setting) must be that CSV's; --peers runs the peers first, so that they are checked against a new run.

Usage: /usr/bin/python3 benchmarks/claims.py [--build build] [--repetitions 5] [--tolerance 0.1]
       [--quick] [--peers] [--save m.json | --load m.json]
--save/--load: keep one run's measurements and check the docs against them again after an edit.
--quick: one short repetition per benchmark (a smoke run: the output's form, not the figures).
Exit status 0 when it ran (whatever the verdicts), 2 when a benchmark program failed.
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


class Claim:
    """One quoted figure: doc, a regex whose group 1 is the figure (a number with k/M/ms/µs, or a
    range a–b), what measures it, and whether larger is better (a rate) or worse (a time)."""

    def __init__(self, name, doc, pattern, measure, unit, scale=1.0, rate=True, invert=False, whole_range=False):
        self.name, self.doc, self.pattern, self.measure = name, doc, pattern, measure
        self.unit, self.scale, self.rate, self.invert = unit, scale, rate, invert
        # whole_range: the figure is a range over scenes; both of its ends must match the measured
        # [min, max] (not merely overlap it).
        self.whole_range = whole_range


# measure = (program, benchmark name, counter) or ("ratio", (program, name, counter), (program, name, counter))
VB, LB, SB = "vibro_bench", "vibro_loads_bench", "vibro_startup_bench"
CLAIMS = [
    Claim("start-up: vibro --version over /bin/true", "docs/index.md",
          r"`vibro --version` costs ([0-9.–]+) ms of CPU more than a bare process", (SB, "BM_VibroVersion", "over_bare_ms"),
          "ms", rate=False),
    Claim("start-up: 20-period Fig. 8 run over /bin/true", "docs/index.md",
          r"a 20-period run ([0-9.–]+) ms", (SB, "BM_VibroSimulate20Periods", "over_bare_ms"), "ms", rate=False),
    Claim("events/s, Fig. 8 (BM_Events1Dof)", "docs/index.md", r"\| Fig\. 8, 1 DOF \| ([0-9.]+ ?[kM]) \|",
          (VB, "BM_Events1Dof", "events/s"), "events/s"),
    Claim("events/s, Fig. 8 (BM_Events1Dof)", "README.md", r"the exact engine runs ([0-9.]+ ?[kM]) events per\s+CPU second on Fig\. 8",
          (VB, "BM_Events1Dof", "events/s"), "events/s"),
    Claim("events/s, Fig. 5 end to end", "docs/index.md", r"\| Fig\. 5, end to end \| ([0-9.]+ ?[kM]) \|",
          (VB, "BM_Fig5StickingEndToEnd", "events/s"), "events/s"),
    Claim("events/s, 2-DOF chain", "docs/index.md", r"\| 2-DOF chain \| ([0-9.]+ ?[kM]) \|",
          (VB, "BM_Events2Dof", "events/s"), "events/s"),
    Claim("events/s, 3-DOF chain", "docs/index.md", r"\| 3-DOF chain \| ([0-9.]+ ?[kM]) \|",
          (VB, "BM_Events3Dof", "events/s"), "events/s"),
    Claim("events/s, 10-DOF stiff chain", "docs/index.md", r"\| 10-DOF stiff chain[^|]*\| ([0-9.]+ ?[kM]) \|",
          (VB, "BM_Events10DofStiff", "events/s"), "events/s"),
    Claim("µs per event, 50-mode beam", "docs/index.md", r"\| 50-node beam, 50 modes \| ([0-9.]+) µs per event",
          (VB, "BM_BeamModes/50", "events/s"), "µs", scale=1e6, rate=False, invert=True),
    Claim("HDF5 store: speed kept, simulation thread", "docs/index.md", r"HDF5 store keeps ([0-9.–]+) of its",
          (VB, "BM_Fig8StoreRatio", "store_speed_thread_cpu"), ""),
    Claim("HDF5 store: speed kept, simulation thread", "docs/performance.md",
          r"a long run keeps \*\*([0-9.–]+)\*\* of its", (VB, "BM_Fig8StoreRatio", "store_speed_thread_cpu"), ""),
    Claim("HDF5 store: speed kept, process CPU", "docs/performance.md",
          r"simulation's thread \(median [0-9.]+\), ([0-9.–]+) of it counted", (VB, "BM_Fig8StoreRatio", "store_speed_process_cpu"), ""),
    Claim("HDF5 store: speed kept, wall time", "docs/performance.md",
          r"whole process's CPU and ([0-9.–]+) in wall", (VB, "BM_Fig8StoreRatio", "store_speed_wall"), ""),
    Claim("events/s without the store (output.md)", "docs/output.md", r"over 2000 periods: ([0-9.]+ ?[kM]) events/s without",
          (VB, "BM_Fig8NoStore", "events/s"), "events/s"),
    Claim("events/s with the store (output.md)", "docs/output.md", r"without it, ([0-9.]+ ?[kM]) events/s\s+with it",
          (VB, "BM_Fig8Store", "events/s"), "events/s"),
    Claim("samples/s without the store (output.md)", "docs/output.md", r"64 samples per period ([0-9.]+ ?[kM]) →",
          (VB, "BM_Fig8NoStoreSamples64", "samples/s"), "samples/s"),
    Claim("samples/s with the store (output.md)", "docs/output.md", r"64 samples per period [0-9.]+ ?[kM] → ([0-9.]+ ?[kM]) samples/s",
          (VB, "BM_Fig8StoreSamples64", "samples/s"), "samples/s"),
    Claim("start-up: vibro --version (perf. table)", "docs/performance.md",
          r"\| `vibro --version` \| [^|]+ \| \*\*([0-9.–]+) ms\*\*", (SB, "BM_VibroVersion", "over_bare_ms"), "ms", rate=False),
    Claim("start-up: 20-period run (perf. table)", "docs/performance.md",
          r"\| `vibro simulate fig08_preload\.toml --set run\.periods=20` \| [^|]+ \| \*\*([0-9.–]+) ms\*\*",
          (SB, "BM_VibroSimulate20Periods", "over_bare_ms"), "ms", rate=False),
    Claim("libraries at start-up: ldd lines", "docs/performance.md", r"`ldd build/vibro` lists ([0-9]+) lines",
          ("command", "ldd"), "lines", rate=False),
    Claim("engine limit: Fig. 8 events/s", "docs/performance.md",
          r"\*\*Now\*\* \(the claims check[^)]*\): Fig\. 8 \(`BM_Events1Dof`\) ([0-9.]+ ?[kM]) events/s",
          (VB, "BM_Events1Dof", "events/s"), "events/s"),
    Claim("engine limit: sincos limit events/s", "docs/performance.md",
          r"the sincos limit \(`BM_Limit_Sincos`\) ([0-9.]+ ?[kM]) events/s", (VB, "BM_Limit_Sincos", "events/s"), "events/s"),
    Claim("engine limit: engine / limit", "docs/performance.md", r"engine / limit \*\*([0-9.]+)\*\* \(",
          ("ratio", (VB, "BM_Events1Dof", "events/s"), (VB, "BM_Limit_Sincos", "events/s")), ""),
    Claim("engine limit: probes per event", "docs/performance.md", r"limit \*\*[0-9.]+\*\* \([^)]*\), ([0-9.]+) probes per event",
          (VB, "BM_Events1Dof", "probes/event"), "", rate=False),
    Claim("engine limit: one sincos", "docs/performance.md", r"probes per event, one sincos ([0-9.]+) ns",
          (VB, "BM_Limit_Sincos", "s/sincos"), "ns", scale=1e9, rate=False),
    Claim("engine limit: one probe alone", "docs/performance.md", r"one probe alone ([0-9.]+) ns",
          (VB, "BM_Fig8GapProbe", "s/probe"), "ns", scale=1e9, rate=False),
    Claim("engine limit: run CPU per probe", "docs/performance.md", r"([0-9.]+) ns of run CPU per probe \(now\)",
          (VB, "BM_Events1Dof", "s/probe"), "ns", scale=1e9, rate=False),
    Claim("basin cells/s, 1 thread, full periods", "docs/performance.md",
          r"every cell runs 100 periods\) \| ([0-9 ]+) cells/s", (VB, "Basin/threads:1/early_stop:0", "cells/s"), "cells/s"),
    Claim("basin cells/s, 2 threads, full periods", "docs/performance.md",
          r"every cell runs 100 periods\) \| [0-9 ]+ cells/s \| ([0-9 ]+) cells/s", (VB, "Basin/threads:2/early_stop:0", "cells/s"),
          "cells/s"),
    Claim("continuation, 1-DOF points/s (perf.)", "docs/performance.md", r"dense branches, the same run\): 1-DOF\s+([0-9 ]+) points/s",
          (VB, "BM_Continue1Dof/1000", "points_per_s"), "points/s"),
    Claim("continuation, 3-DOF re-parse / set in place", "docs/orbits.md", r"which is\s+([0-9.]+) times faster",
          ("ratio", (VB, "BM_Continue3Dof/1000", "points_per_s"), (VB, "BM_Continue3DofReparse/1000", "points_per_s")), ""),
    Claim("proof time, damped 2-DOF three-impact orbit", "docs/prove.md", r"three-impact orbit \(f = 3\) ([0-9.]+) ms",
          (VB, "BM_Prove2DofDampedImpact", "cpu_time"), "ms", rate=False),
    Claim("proof time, damped 3-DOF clearance chain", "docs/prove.md", r"clearance\s+chain ([0-9.]+) ms",
          (VB, "BM_Prove3DofDampedImpact", "cpu_time"), "ms", rate=False),
    Claim("proof time, damped tube with two contacts", "docs/prove.md", r"tube with two contacts ([0-9.]+) ms",
          (VB, "BM_Prove2DofTwoSidedTube", "cpu_time"), "ms", rate=False),
    Claim("several contacts: µs per event, 1 contact", "docs/contacts.md", r"1, 2, 4 and 8 contacts[^:]*:\s+([0-9.]+),",
          (VB, "BM_ChainContacts/1", "s/event"), "µs", scale=1e6, rate=False),
    Claim("several contacts: µs per event, 2 contacts", "docs/contacts.md",
          r"1, 2, 4 and 8 contacts[^:]*:\s+[0-9.]+, ([0-9.]+),", (VB, "BM_ChainContacts/2", "s/event"), "µs",
          scale=1e6, rate=False),
    Claim("several contacts: µs per event, 4 contacts", "docs/contacts.md",
          r"1, 2, 4 and 8 contacts[^:]*:\s+[0-9.]+, [0-9.]+, ([0-9.]+) and", (VB, "BM_ChainContacts/4", "s/event"),
          "µs", scale=1e6, rate=False),
    Claim("several contacts: µs per event, 8 contacts", "docs/contacts.md",
          r"1, 2, 4 and 8 contacts[^:]*:\s+[0-9.]+, [0-9.]+, [0-9.]+ and ([0-9.]+) µs", (VB, "BM_ChainContacts/8", "s/event"),
          "µs", scale=1e6, rate=False),
    Claim("loads: Fig. 8 events/s without loads", "docs/loads.md",
          r"\| Fig\. 8 \(`fig08_preload.toml`\) \| ([0-9.]+ ?[kM]) \|", (LB, "BM_LoadsFig8", "plain_events/s"), "events/s"),
    Claim("loads: Fig. 8 events/s with loads", "docs/loads.md",
          r"\| Fig\. 8 \(`fig08_preload.toml`\) \| [^|]+ \| ([0-9.]+ ?[kM]) \|", (LB, "BM_LoadsFig8", "loads_events/s"), "events/s"),
    Claim("loads: chain3.toml events/s without loads", "docs/loads.md",
          r"\| 3-DOF chain, r = 0 \(`chain3.toml`[^|]*\| ([0-9.]+ ?[kM]) \|", (LB, "BM_LoadsChain3Sticking", "plain_events/s"),
          "events/s"),
    Claim("loads/plain, Fig. 8", "docs/loads.md", r"\| Fig\. 8 \(`fig08_preload.toml`\) \|[^|]*\|[^|]*\| ([0-9.]+) \|",
          (LB, "BM_LoadsFig8", "loads/plain"), ""),
    Claim("loads/plain, 3-DOF chain as BM_Events3Dof", "docs/loads.md",
          r"\| 3-DOF chain as `BM_Events3Dof`[^|]*\|[^|]*\|[^|]*\| ([0-9.]+) \|", (LB, "BM_LoadsChain3", "loads/plain"), ""),
    Claim("loads/plain, 3-DOF chain r = 0.5", "docs/loads.md",
          r"\| 3-DOF chain, r = 0\.5 \(chattering, sticking\) \|[^|]*\|[^|]*\| ([0-9.]+) \|",
          (LB, "BM_LoadsChain3Chattering", "loads/plain"), ""),
    Claim("loads/plain, chain3.toml", "docs/loads.md",
          r"\| 3-DOF chain, r = 0 \(`chain3.toml`[^|]*\|[^|]*\|[^|]*\| ([0-9.]+) \|",
          (LB, "BM_LoadsChain3Sticking", "loads/plain"), ""),
    Claim("Lyapunov cost, Fig. 8", "docs/performance.md", r"\| Fig\. 8, 1 DOF \(`fig08_preload.toml`\) \| [0-9.]+ \| \*\*([0-9.]+)\*\* \|",
          (VB, "BM_LyapunovCost_Fig8", "with/without"), "", rate=False),
    Claim("Lyapunov cost, 2-DOF chain", "docs/performance.md", r"\| 2-DOF chain \(`chain2.toml`\) \| [0-9.]+ \| \*\*([0-9.]+)\*\* \|",
          (VB, "BM_LyapunovCost_Chain2", "with/without"), "", rate=False),
    Claim("Lyapunov cost, 3-DOF chain as BM_Events3Dof", "docs/performance.md",
          r"\| 3-DOF chain as `BM_Events3Dof`[^|]*\| [0-9.]+ \| \*\*([0-9.]+)\*\* \|",
          (VB, "BM_LyapunovCost_Chain3", "with/without"), "", rate=False),
    Claim("Lyapunov cost, chain3.toml", "docs/performance.md",
          r"\| 3-DOF chain as shipped \(`chain3.toml`[^|]*\| [0-9.]+ \| \*\*([0-9.]+)\*\* \|",
          (VB, "BM_LyapunovCost_Chain3Sticking", "with/without"), "", rate=False),
    Claim("Lyapunov cost, chaotic 2-DOF", "docs/performance.md",
          r"\| chaotic 2-DOF \(`chaotic/chain2_sticking.toml`\) \| [0-9.]+ \| \*\*([0-9.]+)\*\* \|",
          (VB, "BM_LyapunovCost_Chain2Chaotic", "with/without"), "", rate=False),
    Claim("proof time, Fig. 5 single-impact orbit", "docs/prove.md", r"Fig\. 5's single-impact orbit ([0-9.]+) ms",
          (VB, "BM_Prove1DofImpact", "cpu_time"), "ms", rate=False),
    Claim("proof time, Fig. 4 sticking orbit", "docs/prove.md", r"Fig\. 4's sticking orbit ([0-9.]+) ms",
          (VB, "BM_Prove1DofSticking", "cpu_time"), "ms", rate=False),
    Claim("proof time, Fig. 8 chattering orbit", "docs/prove.md", r"then the tail\) ([0-9.]+) ms",
          (VB, "BM_Prove1DofChattering", "cpu_time"), "ms", rate=False),
    Claim("proof time, 2-DOF six-impact orbit", "docs/prove.md", r"\(f = 5\) ([0-9.]+) ms",
          (VB, "BM_Prove2DofImpact", "cpu_time"), "ms", rate=False),
    Claim("orbit solve, 1-DOF", "docs/orbits.md", r"one run\): 1-DOF ([0-9.]+) ms", (VB, "BM_Orbit1Dof", "cpu_time"),
          "ms", rate=False),
    Claim("orbit solve, 2-DOF", "docs/orbits.md", r"\n2-DOF ([0-9.]+) ms", (VB, "BM_Orbit2Dof", "cpu_time"), "ms", rate=False),
    Claim("orbit solve, 3-DOF", "docs/orbits.md", r"3-DOF ([0-9.]+) ms, damped", (VB, "BM_Orbit3Dof", "cpu_time"), "ms",
          rate=False),
    Claim("orbit solve, 10-DOF stiff chain", "docs/orbits.md", r"10-DOF stiff chain ([0-9.]+) ms",
          (VB, "BM_Orbit10Dof", "cpu_time"), "ms", rate=False),
    Claim("continuation, 1-DOF points/s", "docs/orbits.md", r"dense branches\): 1-DOF ([0-9 ]+) points/s",
          (VB, "BM_Continue1Dof/1000", "points_per_s"), "points/s"),
    Claim("continuation, 2-DOF points/s", "docs/orbits.md", r"\n2-DOF ([0-9 ]+)/s", (VB, "BM_Continue2Dof/1000", "points_per_s"),
          "points/s"),
    Claim("continuation, 3-DOF points/s", "docs/orbits.md", r"3-DOF ([0-9 ]+)/s, so", (VB, "BM_Continue3Dof/1000", "points_per_s"),
          "points/s"),
    Claim("proof time, tube grazing", "docs/prove.md", r"both Krawczyk tests, the gaps\) ([0-9.]+) ms",
          (VB, "BM_ProveTubeGrazing", "cpu_time"), "ms", rate=False),
    Claim("proof time, 2-DOF sticking orbit (r = 0)", "docs/prove.md", r"the 2-DOF chain ([0-9.]+) ms, damped",
          (VB, "BM_Prove2DofSticking", "cpu_time"), "ms", rate=False),
    Claim("proof time, damped 2-DOF sticking orbit", "docs/prove.md", r"ms, damped\s+([0-9.]+) ms, the 3-DOF chain",
          (VB, "BM_Prove2DofDampedSticking", "cpu_time"), "ms", rate=False),
    Claim("proof time, 3-DOF sticking orbit", "docs/prove.md", r"the 3-DOF chain ([0-9.]+) ms \(within the 1 s",
          (VB, "BM_Prove3DofSticking", "cpu_time"), "ms", rate=False),
    Claim("harmonics: s/probe, H = 1", "docs/harmonics.md", r"\| 1 \| ([0-9.]+) ns \|",
          (VB, "BM_HarmonicsGapProbe/1", "s/probe"), "ns", scale=1e9, rate=False),
    Claim("harmonics: s/probe, H = 2", "docs/harmonics.md", r"\| 2 \| ([0-9.]+) ns \|",
          (VB, "BM_HarmonicsGapProbe/2", "s/probe"), "ns", scale=1e9, rate=False),
    Claim("harmonics: s/probe, H = 3", "docs/harmonics.md", r"\| 3 \| ([0-9.]+) ns \|",
          (VB, "BM_HarmonicsGapProbe/3", "s/probe"), "ns", scale=1e9, rate=False),
    Claim("harmonics: s/probe, H = 4", "docs/harmonics.md", r"\| 4 \| ([0-9.]+) ns \|",
          (VB, "BM_HarmonicsGapProbe/4", "s/probe"), "ns", scale=1e9, rate=False),
    Claim("harmonics: probe H = 2 / H = 1", "docs/harmonics.md", r"\| 2 \| [0-9.]+ ns \| ([0-9.]+) \|",
          ("ratio", (VB, "BM_HarmonicsGapProbe/2", "s/probe"), (VB, "BM_HarmonicsGapProbe/1", "s/probe")), "",
          rate=False),
    Claim("harmonics: probe H = 3 / H = 1", "docs/harmonics.md", r"\| 3 \| [0-9.]+ ns \| ([0-9.]+) \|",
          ("ratio", (VB, "BM_HarmonicsGapProbe/3", "s/probe"), (VB, "BM_HarmonicsGapProbe/1", "s/probe")), "",
          rate=False),
    Claim("harmonics: probe H = 4 / H = 1", "docs/harmonics.md", r"\| 4 \| [0-9.]+ ns \| ([0-9.]+) \|",
          ("ratio", (VB, "BM_HarmonicsGapProbe/4", "s/probe"), (VB, "BM_HarmonicsGapProbe/1", "s/probe")), "",
          rate=False),
    Claim("basin cells/s, 1 thread, early stops", "docs/performance.md", r"\| early stops \(default\) \| ([0-9 ]+) cells/s",
          (VB, "Basin/threads:1/early_stop:1", "cells/s"), "cells/s"),
    Claim("basin cells/s, 2 threads, early stops", "docs/performance.md",
          r"\| early stops \(default\) \| [0-9 ]+ cells/s \| ([0-9 ]+) cells/s", (VB, "Basin/threads:2/early_stop:1", "cells/s"), "cells/s"),
]
# The peers' figures, read from the peers run's CSV (docs/peers.csv; --peers runs it again first):
# per scene the peer's most accurate setting (as benchmarks/peers/table.py), its in-process call
# against a whole vibro process (×CW), as a range over the chattering and several-contact scenes.
PEERS_CSV = os.path.join(ROOT, "docs", "peers.csv")
CHATTERING_AND_CONTACTS = ("fig08_preload.toml", "fig05_coexistence.toml", "chain2.toml", "chain2_damped.toml",
                           "contacts_two_sided_1dof.toml", "contacts_preload_clearance_1dof.toml",
                           "contacts_chain2.toml", "contacts_impact_pair.toml", "contacts_beam3.toml")
NON_CHATTERING = ("fig04_subharmonic.toml", "fig11_clearance.toml")
for doc, scipy_pat, siconos_pat, quiet_pat in (
        ("README.md", r"in-process call costing ([0-9–]+) times a whole", r"Moreau–Jean[^.]*?reaches [^ ]+ T at ([0-9–]+) times",
         r"SciPy reaches 1e-13 T at ([0-9–]+) times"),
        ("docs/index.md", r"in-process call costing\s+([0-9–]+) times a whole", r"Moreau–Jean[^.]*?reaches [^ ]+ T at ([0-9–]+) times",
         r"SciPy reaches 1e-13 T at ([0-9–]+) times"),
        ("docs/peers.md", r"its call costs ([0-9–]+) times a whole vibro process \(×CW\)",
         r"its call costs ([0-9–]+) times a whole vibro process\. Where", None)):
    CLAIMS.append(Claim("peers: SciPy best, call vs vibro process", doc, scipy_pat,
                        ("peers", "SciPy DOP853", CHATTERING_AND_CONTACTS), "×", whole_range=True))
    CLAIMS.append(Claim("peers: Siconos T/1e4, call vs vibro process", doc, siconos_pat,
                        ("peers", "Siconos Moreau–Jean", CHATTERING_AND_CONTACTS), "×", whole_range=True))
    if quiet_pat:
        CLAIMS.append(Claim("peers: SciPy best on Fig. 4 and 11", doc, quiet_pat,
                            ("peers", "SciPy DOP853", NON_CHATTERING), "×", whole_range=True))


def peers_ratios(engine, scenes):
    """×CW of `engine`'s most accurate completed run on each scene of docs/peers.csv."""
    import csv
    if not os.path.exists(PEERS_CSV):
        return None
    with open(PEERS_CSV, newline="", encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh))
    vals = []
    for f in scenes:
        runs = [r for r in rows if r["scene_file"] == f and r["engine"] == engine and r["status"] == "ok"
                and r["event_error"] not in ("", "nan")]
        if runs:
            vals.append(float(min(runs, key=lambda r: float(r["event_error"]))["call_vs_whole"]))
    return vals or None


NOT_REMEASURED = [
    ("docs/performance.md", "before/after tables against commit eca2cf0 and the other engines before a change",
     "history: the ratios against an older commit need that commit built; the current rates are checked above"),
    ("docs/chattering.md", "chattering treatment before/after (ms per run)", "history of one change"),
    ("docs/engines.md", "CVODE settings' cost (ms per run)", "measured by benchmarks/work_precision.py"),
    ("docs/index.md, docs/studies.md", "the 512 × 512 basin in 9.7 s / 21 s",
     "a minute-long CLI run: docs/performance.md gives its command; cells/s of the same study are checked above"),
    ("docs/peers.md", "the peers' tables (each scene and setting)", "printed from docs/peers.csv by "
     "benchmarks/peers/table.py; the ranges the docs quote are checked above against that CSV (--peers runs it anew)"),
    ("docs/performance.md", "the beam's mode sweep (µs per event and per probe, 1-50 modes)",
     "benchmarks/mode_sweep.py writes docs/mode_sweep.csv; the 50-mode cost is checked above"),
    ("docs/performance.md", "modal truncation and work-precision CPU (ms per run)",
     "benchmarks/modal_truncation.py and work_precision.py, whole CLI runs"),
    ("docs/index.md, docs/python.md", "quickstart.sh and test.sh times (minutes)", "a fresh Debian install"),
    ("docs/cli.md", "a sweep's Lyapunov cost (0.85 s against 0.62 s of CPU)", "a whole CLI sweep; the per-run "
     "Lyapunov cost is checked above"),
    ("docs/validation.md", "vibro score's preparation per row (0.1-0.4 ms)", "an order of magnitude for the stop's latency"),
]

NUMBER = re.compile(r"([0-9][0-9 ]*(?:\.[0-9]+)?)\s*([kM]?)")


def parse_claim(text, scale_unit):
    """(lo, hi) of a figure as written: '1.42 M', '823k', '1.36–1.38', '2 860'."""
    parts = re.split(r"–|-(?=[0-9])", text.strip())
    values = []
    for p in parts:
        m = NUMBER.match(p.strip())
        if not m:
            return None
        v = float(m.group(1).replace(" ", ""))
        v *= {"": 1.0, "k": 1e3, "M": 1e6}[m.group(2)]
        values.append(v)
    return min(values), max(values)


def run_benchmarks(build, program, names, repetitions, quick):
    """{benchmark name: {counter: [value per repetition]}} of one program run."""
    exe = os.path.join(build, "benchmarks", program)
    pattern = "^(" + "|".join(re.escape(n) for n in sorted(set(names))) + ")(/min_time:.*|/real_time|/manual_time)*$"
    cmd = [exe, f"--benchmark_filter={pattern}", "--benchmark_format=json",
           f"--benchmark_repetitions={1 if quick else repetitions}", "--benchmark_report_aggregates_only=false",
           "--benchmark_enable_random_interleaving=true"]
    if quick:
        cmd.append("--benchmark_min_time=0.01")
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        raise RuntimeError(f"{program} failed (exit {p.returncode}): {p.stderr[-500:]}")
    out = {}
    for b in json.loads(p.stdout)["benchmarks"]:
        if b.get("run_type") != "iteration":
            continue
        name = "/".join(x for x in b["run_name"].split("/")
                        if not re.match(r"(min_time:|repeats:|real_time$|manual_time$)", x))
        row = out.setdefault(name, {})
        to_ms = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}[b.get("time_unit", "ns")]
        row.setdefault("cpu_time", []).append(b["cpu_time"] * to_ms)  # CPU per iteration, ms
        for k, v in b.items():
            if isinstance(v, (int, float)) and k not in ("cpu_time", "real_time", "iterations", "repetitions",
                                                         "repetition_index", "threads", "family_index",
                                                         "per_family_instance_index"):
                row.setdefault(k, []).append(float(v))
    return out


def ldd_lines(build):
    """Lines of `ldd build/vibro`: the libraries every vibro process maps at start-up."""
    p = subprocess.run(["ldd", os.path.join(build, "vibro")], capture_output=True, text=True)
    return len([x for x in p.stdout.splitlines() if x.strip()])


def measured(claim, results):
    """(median, min, max) of a claim's measurement in its unit, or None."""
    m = claim.measure
    if m[0] == "ratio":
        num, den = (results.get(x[0], {}).get(x[1], {}).get(x[2]) for x in m[1:])
        if not num or not den:
            return None
        vals = [a / b for a, b in zip(num, den)]
    elif m[0] == "peers":
        vals = peers_ratios(m[1], m[2])
        if not vals:
            return None
    elif m[0] == "command":
        vals = results.get("command", {}).get(m[1], {}).get(claim.unit)
        if not vals:
            return None
    else:
        vals = results.get(m[0], {}).get(m[1], {}).get(m[2])
        if not vals:
            return None
        vals = [(1.0 / v if claim.invert else v) * claim.scale for v in vals]
    return statistics.median(vals), min(vals), max(vals)


def verdict(claim, lo_hi, meas, tol):
    lo, hi = lo_hi
    med, mlo, mhi = meas
    if claim.whole_range:
        if abs(lo - mlo) <= tol * mlo and abs(hi - mhi) <= tol * mhi:
            return "holds"
        return "differs"
    if mhi * (1 + tol) >= lo and mlo * (1 - tol) <= hi:
        return "holds"
    above = mlo * (1 - tol) > hi
    return ("faster" if above else "slower") if claim.rate else ("slower" if above else "faster")


def show(x):
    if x is None:
        return "—"
    a = abs(x)
    if a >= 1e6:
        return f"{x / 1e6:.3g} M"
    if a >= 1e4:
        return f"{x / 1e3:.3g}k"
    if a >= 100:
        return f"{x:.0f}"
    return f"{x:.3g}"


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--build", default=os.path.join(ROOT, "build"))
    ap.add_argument("--repetitions", type=int, default=5)
    ap.add_argument("--tolerance", type=float, default=0.10)
    ap.add_argument("--quick", action="store_true", help="one short repetition each (a smoke run)")
    ap.add_argument("--peers", action="store_true", help="also run benchmarks/peers/run_all.py")
    ap.add_argument("--save", metavar="JSON", help="write the measurements to JSON (to check edited docs later)")
    ap.add_argument("--load", metavar="JSON", help="check the docs against the measurements of an earlier --save "
                    "instead of measuring")
    args = ap.parse_args()
    texts = {}
    for c in CLAIMS:
        if c.doc not in texts:
            with open(os.path.join(ROOT, c.doc), encoding="utf-8") as fh:
                texts[c.doc] = fh.read()
    wanted = {}
    for c in CLAIMS:
        if c.measure[0] in ("command", "peers"):
            continue
        for x in ([c.measure[1], c.measure[2]] if c.measure[0] == "ratio" else [c.measure]):
            wanted.setdefault(x[0], set()).add(x[1])
    failed = False
    if args.peers and not args.load:  # first, so that the peers' claims are checked against this run
        subprocess.run([sys.executable, os.path.join(ROOT, "benchmarks", "peers", "run_all.py")], check=False)
    if args.load:
        with open(args.load, encoding="utf-8") as fh:
            saved = json.load(fh)
        results, args.repetitions, args.quick = saved["results"], saved["repetitions"], saved["quick"]
        wanted = {}
        print(f"measurements of {saved['when']} (commit {saved['commit']}), read from {args.load}")
    else:
        results = {"command": {"ldd": {"lines": [float(ldd_lines(args.build))]}}}
    for program, names in wanted.items():
        try:
            results[program] = run_benchmarks(args.build, program, names, args.repetitions, args.quick)
        except (RuntimeError, OSError, json.JSONDecodeError) as e:
            print(f"error: {e}", file=sys.stderr)
            failed = True
    if args.save:
        commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
        with open(args.save, "w", encoding="utf-8") as fh:
            json.dump({"when": time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()), "commit": commit,
                       "load_average": os.getloadavg()[0], "repetitions": args.repetitions, "quick": args.quick,
                       "results": results}, fh, indent=1)
    print(f"claims check: {len(CLAIMS)} figures, {1 if args.quick else args.repetitions} repetition(s) each, "
          f"tolerance {args.tolerance:.0%}{' (quick: the form only, not the figures)' if args.quick else ''}")
    print(f"{'claim':46s} | {'where':20s} | {'claimed':>13s} | {'measured median [min, max]':>30s} | verdict")
    counts = {}
    for c in CLAIMS:
        found = re.findall(c.pattern, texts[c.doc])
        lo_hi = parse_claim(found[0], c.unit) if len(found) == 1 else None
        meas = measured(c, results)
        if lo_hi is None:
            v = "missing" if not found else ("ambiguous" if len(found) > 1 else "unreadable")
        elif meas is None:
            v = "not measured"
        else:
            v = verdict(c, lo_hi, meas, args.tolerance)
        counts[v] = counts.get(v, 0) + 1
        claimed = "—" if lo_hi is None else (show(lo_hi[0]) if lo_hi[0] == lo_hi[1] else
                                             f"{show(lo_hi[0])}–{show(lo_hi[1])}")
        got = "—" if meas is None else f"{show(meas[0])} [{show(meas[1])}, {show(meas[2])}]"
        print(f"{c.name:46s} | {c.doc:20s} | {claimed + ' ' + c.unit:>13s} | {got + ' ' + c.unit:>30s} | {v}")
    for doc, what, why in NOT_REMEASURED:
        print(f"not re-measured: {doc}: {what} ({why})")
    print("summary: " + ", ".join(f"{k} {n}" for k, n in sorted(counts.items())))
    return 2 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
