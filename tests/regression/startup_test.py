#!/usr/bin/python3
"""What a `vibro` process loads (docs/performance.md, "Start-up"): the libraries the dynamic
loader initialises, from its own trace (LD_DEBUG=libs, "calling init: PATH"), not from timings, so
the test holds on any machine and under any load.

    startup_test.py VIBRO SCENES_DIR [--mpiexec MPIEXEC] [--static-libstdcxx]

  * `vibro --version` and a 20-period `vibro simulate` without --out load no HDF5, no libcurl, no
    GnuTLS, no MPI library, not the prover's Arb, FLINT, NTL, gf2x, MPFR or GMP, no SUNDIALS and
    no oneTBB (the CVODE engine and the parallel loops are plugins), and no libfmt, toml++ or
    libquadmath (compiled into libvibro);
  * the same run with --out loads HDF5, `vibro prove` the prover plugin with Arb and FLINT, a run
    with run.engine = "cvode" the CVODE plugin with SUNDIALS, and a basin the parallel-loop plugin
    with oneTBB (so the trace does see a library loaded at first use: the checks above can fail);
  * with --mpiexec, a basin under `mpirun -np 2` loads the MPI plugin and libmpi (each rank);
  * with --static-libstdcxx (the build's VIBRO_STATIC_LIBSTDCXX), `vibro --version`, the run without
    --out and the CVODE run load no libstdc++.so (linked into libvibro, vibro and the CVODE plugin),
    while the basin, whose oneTBB needs it, still loads it and runs with it.
The speed itself is measured by benchmarks/startup_bench.cpp.
"""
import os
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402

HEAVY = re.compile(r"lib(hdf5|curl|gnutls|mpi|open-pal|open-rte|hwloc|vibro_mpi|vibro_prove|flint|arb|ntl|gf2x|mpfr|gmp"
                   r"|vibro_cvode|sundials|vibro_parallel|tbb|fmt|tomlplusplus|quadmath)[^/]*\.so")


def traced(cmd, work, env=None):
    """(exit code, {pid: [paths of the libraries the loader initialised]}, output): the trace of
    each process (mpirun's ranks included) in its own file, LD_DEBUG_OUTPUT.PID."""
    trace = tempfile.mkdtemp(dir=work)
    e = dict(os.environ if env is None else env, LD_DEBUG="libs", LD_DEBUG_OUTPUT=os.path.join(trace, "ld"))
    p = subprocess.run(cmd, capture_output=True, text=True, env=e, timeout=600)
    per_process = {}
    for name in os.listdir(trace):
        with open(os.path.join(trace, name), errors="replace") as fh:
            per_process[name] = re.findall(r"calling init: (\S+)", fh.read())
    return p.returncode, per_process, p.stdout + p.stderr


def loaded(cmd, work, env=None):
    """(exit code, [libraries initialised by the one process], output)."""
    rc, per_process, out = traced(cmd, work, env)
    libs = [p for ps in per_process.values() for p in ps]
    return rc, libs, out


def main():
    vibro, scenes = os.path.abspath(sys.argv[1]), sys.argv[2]
    mpiexec = sys.argv[sys.argv.index("--mpiexec") + 1] if "--mpiexec" in sys.argv else None
    static_cxx = "--static-libstdcxx" in sys.argv
    cxx = re.compile(r"libstdc\+\+\.so")
    scene = os.path.join(scenes, "fig08_preload.toml")
    with tempfile.TemporaryDirectory() as work:
        for name, cmd in (("vibro --version", [vibro, "--version"]),
                          ("vibro simulate (20 periods, no --out)",
                           [vibro, "simulate", scene, "--set", "run.periods=20"])):
            rc, libs, out = loaded(cmd, work)
            heavy = [p for p in libs if HEAVY.search(os.path.basename(p))]
            check(f"{name}: exit 0", rc == 0, out[-2000:])
            check(f"{name}: the loader's trace lists libraries", len(libs) >= 5, libs)
            check(f"{name}: loads no HDF5, libcurl, GnuTLS, MPI, Arb, FLINT, NTL, gf2x, MPFR, GMP, SUNDIALS, oneTBB, "
                  "libfmt, toml++ or libquadmath", not heavy, heavy)
            if static_cxx:
                check(f"{name}: loads no libstdc++.so", not any(cxx.search(p) for p in libs), libs)
        h5 = os.path.join(work, "run.h5")
        rc, libs, out = loaded([vibro, "simulate", scene, "--set", "run.periods=20", "--out", h5], work)
        check("vibro simulate --out: exit 0", rc == 0, out[-2000:])
        check("vibro simulate --out: loads HDF5 when it writes the file",
              any(re.search(r"libhdf5[^/]*\.so", os.path.basename(p)) for p in libs), libs)
        rc, libs, out = loaded([vibro, "prove", os.path.join(scenes, "fig05_coexistence.toml"), "--kind", "impact"],
                               work)
        names = [os.path.basename(p) for p in libs]
        check("vibro prove: exit 0", rc == 0, out[-2000:])
        check("vibro prove: loads the prover plugin, Arb and FLINT when it proves",
              all(any(n.startswith(lib) for n in names) for lib in ("libvibro_prove.so", "libflint-arb", "libflint.so")),
              names)
        rc, libs, out = loaded([vibro, "simulate", scene, "--set", "run.periods=20", "--set", 'run.engine="cvode"'], work)
        names = [os.path.basename(p) for p in libs]
        check("vibro simulate, run.engine = \"cvode\": exit 0", rc == 0, out[-2000:])
        check("vibro simulate, run.engine = \"cvode\": loads the CVODE plugin and SUNDIALS CVODE",
              all(any(n.startswith(lib) for n in names) for lib in ("libvibro_cvode.so", "libsundials_cvode")), names)
        if static_cxx:
            check("vibro simulate, run.engine = \"cvode\": loads no libstdc++.so", not any(cxx.search(n) for n in names),
                  names)
        rc, libs, out = loaded([vibro, "basin", os.path.join(scenes, "fig05_coexistence.toml"), "--grid", "3,3",
                                "--threads", "2"], work)
        names = [os.path.basename(p) for p in libs]
        check("vibro basin: exit 0", rc == 0, out[-2000:])
        check("vibro basin: loads the parallel-loop plugin and oneTBB",
              all(any(n.startswith(lib) for n in names) for lib in ("libvibro_parallel.so", "libtbb")), names)
        if static_cxx:
            check("vibro basin: oneTBB brings libstdc++.so beside libvibro's own copy",
                  any(cxx.search(n) for n in names), names)
        if mpiexec:
            env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
            rc, per_process, out = traced([mpiexec, "-np", "2", "--oversubscribe", vibro, "basin",
                                           os.path.join(scenes, "fig05_coexistence.toml"), "--grid", "4,4"],
                                          work, env)
            ranks = [[os.path.basename(p) for p in libs] for libs in per_process.values()
                     if any(os.path.basename(p).startswith("libvibro.so") for p in libs)]
            check("mpirun -np 2 vibro basin: exit 0 on 2 ranks", rc == 0 and "2 MPI ranks" in out, out[-2000:])
            check("mpirun -np 2 vibro basin: 2 vibro processes traced", len(ranks) == 2, list(per_process))
            check("mpirun -np 2 vibro basin: each rank loads the MPI plugin and libmpi",
                  all(any(n.startswith("libvibro_mpi.so") for n in r) and any(n.startswith("libmpi.so") for n in r)
                      for r in ranks), ranks)
    finish()


if __name__ == "__main__":
    main()
