#!/usr/bin/python3
"""The claims check runs and its output is well formed (benchmarks/claims.py --quick): one row per
claim with the document it is read from, the figure as the document states it, a measurement and a
verdict; no claim whose text the documents no longer hold. The figures themselves are not judged
here (a quick run measures too briefly): the claims check is run at full length by hand.

    claims_test.py BUILD_DIR
"""
import os
import re
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from checks import check, finish  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
VERDICTS = {"holds", "faster", "slower", "differs"}


def main():
    build = sys.argv[1]
    saved = os.path.join(tempfile.mkdtemp(prefix="vibro_claims_"), "m.json")
    p = subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "benchmarks", "claims.py"), "--quick", "--build", build,
                        "--save", saved], capture_output=True, text=True, timeout=1500)
    check("claims.py --quick: exit 0", p.returncode == 0, p.stderr[-2000:])
    lines = p.stdout.splitlines()
    m = re.match(r"claims check: (\d+) figures", lines[0] if lines else "")
    check("the first line says how many figures", m is not None, lines[:1])
    rows = [ln for ln in lines[2:] if ln.count(" | ") == 4]
    check("one row per figure", m is not None and len(rows) == int(m.group(1)), (len(rows), m and m.group(1)))
    for row in rows:
        name, doc, claimed, got, verdict = [x.strip() for x in row.split(" | ")]
        check(f"{name}: read from an existing document", os.path.exists(os.path.join(ROOT, doc)), doc)
        check(f"{name}: the figure is found in {doc}", not claimed.startswith("—"), row)
        check(f"{name}: measured, with its spread", re.search(r"\[.+, .+\]", got) is not None, row)
        check(f"{name}: a verdict", verdict in VERDICTS, row)
    check("a summary line", any(ln.startswith("summary: ") for ln in lines), lines[-3:])
    # The saved measurements, checked again without measuring, give the same rows.
    q = subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "benchmarks", "claims.py"), "--load", saved],
                       capture_output=True, text=True, timeout=60)
    check("--load: exit 0", q.returncode == 0, q.stderr[-2000:])
    again = [ln for ln in q.stdout.splitlines() if ln.count(" | ") == 4]
    check("--load: the same rows as the run that saved them", again == [ln for ln in lines if ln.count(" | ") == 4],
          (len(again), len(rows)))
    finish()


if __name__ == "__main__":
    main()
