#!/usr/bin/python3
"""A finer sweep of cli.bounded's tight limits (docs/output.md, "Crash safety"): `vibro simulate
--time-limit 0 --out` of tests/regression/bounded_test.py's scene under `ulimit -v` at its process
base + LO … HI MB in STEP MB, REPS times each, the base taken as that test takes it. Counts the exit
codes (a crash is a negative one), checks one line saying "out of memory", and that the file left
is readable (vibro info exit 0 or 2, h5py reads /events/t). With a preloaded allocation counter
(scripts/allocwatch.c) it also counts the refused allocations and those with libhdf5 on the stack.

usage: oom_sweep.py VIBRO LO HI STEP REPS [allocwatch.so]"""
import os, re, resource, subprocess, sys, tempfile
vibro, lo, hi, step, reps = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), float(sys.argv[4]), int(sys.argv[5])
preload = sys.argv[6] if len(sys.argv) > 6 else None
MB = 1 << 20
test = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "regression", "bounded_test.py")
src = re.search(r'f\.write\("""(.*?)"""\)', open(test).read(), re.S).group(1)
tmp = tempfile.mkdtemp(prefix="s39sweep_")
scene = os.path.join(tmp, "tiny_gap.toml")
open(scene, "w").write(src)
needed = [os.path.realpath(l.split("=>")[1].split("(")[0].strip())
          for l in subprocess.run(["ldd", vibro], capture_output=True, text=True).stdout.splitlines()
          if "=>" in l and "/" in l.split("=>")[1]]
env = dict(os.environ)
if preload:
    env["LD_PRELOAD"] = preload
    env["ALLOCWATCH_LOG"] = os.path.join(tmp, "aw.log")
def baseline():
    p = subprocess.Popen([vibro, "simulate", scene, "--time-limit", "0"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, env=env)
    size = None
    while p.poll() is None and size is None:
        try:
            maps = open(f"/proc/{p.pid}/maps").read()
            if "libvibro" in maps and all(n in maps for n in needed):
                for line in open(f"/proc/{p.pid}/status"):
                    if line.startswith("VmSize:"): size = int(line.split()[1]) * 1024
        except OSError:
            pass
    p.kill(); p.wait()
    return size
base = baseline()
print("base", base / MB, "MB", flush=True)
codes, bad = {}, []
k = 0
x = lo
while x <= hi + 1e-9:
    for r in range(reps):
        out = os.path.join(tmp, f"t{k % 2}.h5"); k += 1
        if os.path.exists(out): os.remove(out)
        lim = int(base + x * MB)
        p = subprocess.run([vibro, "simulate", scene, "--time-limit", "0", "--out", out], capture_output=True, text=True,
                           timeout=600, env=env, preexec_fn=lambda: resource.setrlimit(resource.RLIMIT_AS, (lim, lim)))
        codes[p.returncode] = codes.get(p.returncode, 0) + 1
        lines = [l for l in p.stderr.splitlines() if l.strip()]
        ok = p.returncode == 3 and len(lines) == 1 and "out of memory" in p.stderr
        readable = None
        if os.path.exists(out):
            i = subprocess.run([vibro, "info", out], capture_output=True, text=True, timeout=120)
            h = subprocess.run(["/usr/bin/python3", "-c", f"import h5py; f=h5py.File('{out}','r'); print(f['events/t'].shape[0])"],
                               capture_output=True, text=True, timeout=120)
            readable = i.returncode in (0, 2) and "corrupt" not in i.stderr and h.returncode == 0
            rows = h.stdout.strip()
        else:
            rows = "-"
        if not ok or readable is False:
            bad.append((x, r, p.returncode, p.stderr[-200:], readable))
            print("BAD", x, r, p.returncode, repr(p.stderr[-200:]), readable, flush=True)
    x += step
print("exit codes:", codes, "bad:", len(bad), flush=True)
if preload:
    log = open(env["ALLOCWATCH_LOG"]).read()
    print("failed allocations:", log.count("FAIL"), "with libhdf5 on the stack:", log.count("hdf5_on_stack=1"))
