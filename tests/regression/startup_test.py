#!/usr/bin/python3
"""What a `vibro` process loads (docs/performance.md, "Start-up"): the libraries the dynamic
loader initialises, from its own trace (LD_DEBUG=libs, "calling init: PATH"), not from timings, so
the test holds on any machine and under any load.

    startup_test.py VIBRO SCENES_DIR [--mpiexec MPIEXEC]

  * `vibro --version` and a 20-period `vibro simulate` without --out load no HDF5, no libcurl, no
    GnuTLS and no MPI library;
  * the same run with --out loads HDF5 (so the trace does see a library loaded at first use: the
    check above can fail);
  * with --mpiexec, a basin under `mpirun -np 2` loads the MPI plugin and libmpi (each rank).
The speed itself is measured by benchmarks/startup_bench.cpp.
"""
import os
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402

HEAVY = re.compile(r"lib(hdf5|curl|gnutls|mpi|open-pal|open-rte|hwloc|vibro_mpi)[^/]*\.so")


def loaded(cmd, env=None):
    """(exit code, [paths of the libraries the loader initialised], output)."""
    e = dict(os.environ if env is None else env, LD_DEBUG="libs")
    p = subprocess.run(cmd, capture_output=True, text=True, env=e, timeout=600)
    libs = re.findall(r"calling init: (\S+)", p.stderr)
    return p.returncode, libs, p.stdout + p.stderr


def main():
    vibro, scenes = os.path.abspath(sys.argv[1]), sys.argv[2]
    mpiexec = sys.argv[sys.argv.index("--mpiexec") + 1] if "--mpiexec" in sys.argv else None
    scene = os.path.join(scenes, "fig08_preload.toml")
    with tempfile.TemporaryDirectory() as work:
        for name, cmd in (("vibro --version", [vibro, "--version"]),
                          ("vibro simulate (20 periods, no --out)",
                           [vibro, "simulate", scene, "--set", "run.periods=20"])):
            rc, libs, out = loaded(cmd)
            heavy = [p for p in libs if HEAVY.search(os.path.basename(p))]
            check(f"{name}: exit 0", rc == 0, out[-2000:])
            check(f"{name}: the loader's trace lists libraries", len(libs) >= 5, libs)
            check(f"{name}: loads no HDF5, libcurl, GnuTLS or MPI", not heavy, heavy)
        h5 = os.path.join(work, "run.h5")
        rc, libs, out = loaded([vibro, "simulate", scene, "--set", "run.periods=20", "--out", h5])
        check("vibro simulate --out: exit 0", rc == 0, out[-2000:])
        check("vibro simulate --out: loads HDF5 when it writes the file",
              any(re.search(r"libhdf5[^/]*\.so", os.path.basename(p)) for p in libs), libs)
        if mpiexec:
            env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1")
            rc, libs, out = loaded([mpiexec, "-np", "2", "--oversubscribe", vibro, "basin",
                                    os.path.join(scenes, "fig05_coexistence.toml"), "--grid", "4,4"], env)
            names = [os.path.basename(p) for p in libs]
            check("mpirun -np 2 vibro basin: exit 0 on 2 ranks", rc == 0 and "2 MPI ranks" in out, out[-2000:])
            check("mpirun -np 2 vibro basin: each rank loads the MPI plugin and libmpi",
                  sum(n.startswith("libvibro_mpi.so") for n in names) == 2
                  and sum(n.startswith("libmpi.so") for n in names) >= 2, names)
    finish()


if __name__ == "__main__":
    main()
