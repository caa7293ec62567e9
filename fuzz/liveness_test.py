#!/usr/bin/python3
"""The campaigns' liveness judge (campaign.py's StopClock) judged itself: programs that stop at
once, late or never, given to Campaign.run as if they were vibro, each with the verdict it must
get (docs/reliability.md, "Fuzz campaign").

- prompt: exit 130 at once after SIGTERM: no finding;
- busy / sleepy / child: 1.6 s of computing, of sleeping, or of a child process computing that
  it waits for, then exit 130: "slow stop";
- late-exit-0: 1.6 s of computing after the signal, then exit 0: "stop request ignored";
- deaf-busy / deaf-sleep: SIGTERM ignored, computing or sleeping for ever: "hang ignoring SIGTERM";
- child-before: a child process computing since before the signal, stopped (SIGKILL) and waited
  for after it, then exit 130 at once: no finding (the child's CPU before the signal reaches the
  program's own when it waits, and is not the stop's);
- loaded / loaded-exit-0: 0.15 s of computing after the signal, then exit 130 (or 0), while the
  program shares one CPU, at nice 10, with a competing busy process at nice 0: its wall time is
  several seconds (asserted, else the case shows nothing) but its own time is 0.15 s: no finding.
  A judge by wall time reports these.

usage: liveness_test.py [--campaign DIR]   (DIR: the directory of the campaign.py to judge)
Exits 0 when every case gets its verdict.
"""
import argparse
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import textwrap
import time

FAKE = textwrap.dedent('''\
    #!/usr/bin/python3
    import os, signal, subprocess, sys, time
    mode = sys.argv[1]

    def spin(seconds):
        t = time.process_time()
        x = 0
        while time.process_time() - t < seconds:
            x += 1

    def on_stop(signum, frame):
        if mode in ("busy",):
            spin(1.6)
        elif mode == "sleepy":
            time.sleep(1.6)
        elif mode == "child":
            subprocess.run([sys.executable, "-c",
                            "import time\\nt = time.process_time()\\nwhile time.process_time() - t < 1.6: pass"])
        elif mode == "child-before":
            with open(f"/proc/{kid.pid}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            print(f"child cpu {(int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')}", file=sys.stderr,
                  flush=True)
            kid.kill()
            kid.wait()
        elif mode.startswith("loaded"):
            spin(0.15)
        elif mode == "late-exit-0":
            spin(1.6)
            os._exit(0)
        if mode == "loaded-exit-0":
            os._exit(0)
        os._exit(130)

    if mode.startswith("loaded"):
        os.sched_setaffinity(0, {int(os.environ["LIVENESS_CPU"])})
        os.nice(10)
    if mode.startswith("deaf"):
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    else:
        signal.signal(signal.SIGTERM, on_stop)
        signal.signal(signal.SIGINT, on_stop)
    if mode == "child-before":
        kid = subprocess.Popen([sys.executable, "-c", "import time\\nt = time.process_time()\\n"
                                "while time.process_time() - t < 1.3: pass\\ntime.sleep(1000)"])
    print("ready", flush=True)
    if mode == "deaf-busy" or mode.startswith("loaded"):
        while True:
            spin(1.0)
    while True:
        time.sleep(1.0)
''')

CASES = {  # mode: the finding kind it must get (None: none)
    "prompt": None,
    "busy": "slow stop",
    "sleepy": "slow stop",
    "child": "slow stop",
    "child-before": None,
    "late-exit-0": "stop request ignored",
    "deaf-busy": "hang ignoring SIGTERM",
    "deaf-sleep": "hang ignoring SIGTERM",
    "loaded": None,
    "loaded-exit-0": None,
}


def stop_disposition_set(pid):
    """Whether the program has set its disposition of SIGTERM, caught or ignored (SigCgt, SigIgn of
    /proc/PID/status): the fake does so just before it says "ready"."""
    try:
        with open(f"/proc/{pid}/status") as f:
            fields = dict(line.split(":", 1) for line in f if ":" in line)
        masks = int(fields["SigCgt"], 16) | int(fields["SigIgn"], 16)
    except (OSError, KeyError, ValueError):
        return False
    return bool(masks & (1 << (signal.SIGTERM - 1)))


def child_computed(campaign, pid):
    """child-before: the disposition set and the child done with its 1.3 s of computing (asleep
    after more than 1.25 s of CPU)."""
    if not stop_disposition_set(pid):
        return False
    kids = campaign._descendants(pid)
    return bool(kids) and all((campaign.process_cpu(k) or 0.0) >= 1.25 and
                              set(campaign._thread_states(k)) == {"S"} for k in kids)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--campaign", default=os.path.dirname(os.path.abspath(__file__)))
    ap.add_argument("--only", default="")
    a = ap.parse_args()
    sys.path.insert(0, a.campaign)
    import campaign  # noqa: E402
    work = tempfile.mkdtemp(prefix="vibro_liveness_")
    fake = os.path.join(work, "fake")
    with open(fake, "w") as f:
        f.write(FAKE)
    os.chmod(fake, 0o755)
    scenes = os.path.join(work, "scenes")
    os.mkdir(scenes)
    cpu = sorted(os.sched_getaffinity(0))[-1]
    os.environ["LIVENESS_CPU"] = str(cpu)
    failures = 0
    try:
        for mode, want in CASES.items():
            if a.only and mode != a.only:
                continue
            c = campaign.Campaign(fake, scenes, 1, time.monotonic() + 600, work)
            hog = None
            if mode.startswith("loaded"):
                hog = subprocess.Popen([sys.executable, "-c", "while True: pass"],
                                       preexec_fn=lambda: os.sched_setaffinity(0, {cpu}))
            shown = {}

            def moment(pid, mode=mode, shown=shown):
                """The signal once the fake shows it is ready for it (polled, never a fixed delay):
                its SIGTERM disposition set; for child-before, its child done computing too."""
                if child_computed(campaign, pid) if mode == "child-before" else stop_disposition_set(pid):
                    shown["at"] = time.monotonic()
                    return True
                return False
            t0 = time.monotonic()
            try:
                rc, err = c.run("liveness", [mode], signals=[(moment, signal.SIGTERM)], limit=60)
            finally:
                if hog is not None:
                    hog.kill()
                    hog.wait()
            wall = time.monotonic() - shown.get("at", t0)
            kinds = [x["kind"] for x in c.findings]
            got = kinds[0] if kinds else None
            ok = got == want and len(kinds) <= 1
            note = ""
            if mode.startswith("loaded") and wall <= campaign.LIVENESS:
                ok = False
                note = " (no load: the program stopped within the liveness bound of wall time, the case shows nothing)"
            if mode == "child-before":
                got_cpu = [float(x.split()[-1]) for x in err.splitlines() if x.startswith("child cpu")]
                note = f" (the child had computed {got_cpu[0] if got_cpu else '?'} s before the signal)"
                if not got_cpu or got_cpu[0] <= campaign.LIVENESS:
                    ok = False
                    note += ": not past the liveness bound, the case shows nothing"
            failures += not ok
            print(f"{'ok  ' if ok else 'FAIL'} {mode:14s} wall {wall:5.2f} s after the signal; findings {kinds} "
                  f"(expected {want}){note}", flush=True)
            for x in c.findings:
                print(f"       {x['detail'][:300]}")
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"{len([m for m in CASES if not a.only or m == a.only]) - failures} of "
          f"{len([m for m in CASES if not a.only or m == a.only])} cases judged as they must be")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
