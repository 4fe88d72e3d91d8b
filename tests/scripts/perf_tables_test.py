#!/usr/bin/env python3
"""scripts/perf-tables on a 10-row results file: the newest run of each case, units in the
header, figures as printed, a pivot with a ratio across time units, --write then --check, and a
changed figure or a broken marker caught.

Usage: perf_tables_test.py PATH/TO/scripts/perf-tables   (standard library only)
"""
import os
import subprocess
import sys
import tempfile

SCRIPT = sys.argv[1]

RESULTS = """\
date\tcommit\tnproc\tcpu\tmem_GiB\tpart\tcase\tmetric\tvalue\tunit
2026-01-01T09:00Z\taaa\t2\tTest CPU\t8.0\tsvo\tarmadillo 1024 geo\ttime_s\t0.50\ts
2026-01-01T09:00Z\taaa\t2\tTest CPU\t8.0\tsvo\tarmadillo 1024 geo\tvdb/ours\t5.00\tx
2026-01-01T09:00Z\taaa\t2\tTest CPU\t8.0\tsvo\tdragon 1024 geo\ttime_s\t0.11\ts
2026-01-02T09:00Z\tbbb-dirty\t2\tTest CPU\t8.0\tsvo\tarmadillo 1024 geo\ttime_s\t0.20\ts
2026-01-02T09:00Z\tbbb-dirty\t2\tTest CPU\t8.0\tsvo\tarmadillo 1024 geo\tvdb/ours\t18.55\tx
2026-01-02T09:00Z\tbbb-dirty\t2\tTest CPU\t8.0\tsvo\tarmadillo 1024 geo\tsvo_bytes\t582587\tB
2026-01-02T09:00Z\tbbb-dirty\t2\tTest CPU\t8.0\tsvo\tarmadillo 4096 geo\tvoxels\t41690253\tvoxels
2026-01-02T09:00Z\tbbb-dirty\t2\tTest CPU\t8.0\tsvo\tarmadillo 4096 geo\ttime_s\t1.29\ts
2026-01-02\tccc\t2\tunknown\tunknown\timport\tsvokit_import/x.obj\treal_time\t351\tms
2026-01-02\tccc\t2\tunknown\tunknown\timport\topenmesh_read/x.obj\treal_time\t2.493\ts
"""

DOC = """\
# Doc

<!-- tables:begin part=svo metrics=time_s,vdb/ours,svo_bytes,voxels -->
stale
<!-- tables:end -->

Between.

<!-- tables:begin part=import pivot=first ratio=openmesh_read:real_time/svokit_import:real_time -->
<!-- tables:end -->
"""

# The older run's armadillo 1024 figures (0.50 s, 5.00x) are superseded; dragon's, measured in
# that run only, stay, in the order of the rows chosen; bytes are shown in MB, large counts
# grouped, ratios with their sign.
EXPECTED = """\
# Doc

<!-- tables:begin part=svo metrics=time_s,vdb/ours,svo_bytes,voxels -->

*`svo` in [benchmark-results.tsv](benchmark-results.tsv): bbb-dirty (2026-01-02T09:00Z): armadillo 1024 geo, armadillo 4096 geo; aaa (2026-01-01T09:00Z): dragon 1024 geo; 2 cores (Test CPU, 8.0 GiB).*

| case               | time (s) | vdb/ours | svo file (MB) | voxels     |
| ------------------ | -------: | -------: | ------------: | ---------: |
| dragon 1024 geo    |     0.11 |        – |             – |          – |
| armadillo 1024 geo |     0.20 |   18.55× |         0.583 |          – |
| armadillo 4096 geo |     1.29 |        – |             – | 41 690 253 |

<!-- tables:end -->

Between.

<!-- tables:begin part=import pivot=first ratio=openmesh_read:real_time/svokit_import:real_time -->

*`import` in [benchmark-results.tsv](benchmark-results.tsv): ccc (2026-01-02, transcribed); 2 cores.*

| case  | svokit_import (ms) | openmesh_read (s) | openmesh_read / svokit_import |
| ----- | -----------------: | ----------------: | ----------------------------: |
| x.obj |                351 |             2.493 |                         7.10× |

<!-- tables:end -->
"""

failures = 0


def expect(what, ok, detail=""):
    global failures
    if not ok:
        failures += 1
        print(f"FAILED: {what}\n{detail}")


def run(*args):
    return subprocess.run([sys.executable, SCRIPT, *args], capture_output=True, text=True)


with tempfile.TemporaryDirectory() as tmp:
    results, doc = os.path.join(tmp, "results.tsv"), os.path.join(tmp, "doc.md")
    files = ["--results", results, "--doc", doc]

    def write(path, text):
        with open(path, "w", encoding="utf-8") as f:
            f.write(text)

    def read(path):
        with open(path, encoding="utf-8") as f:
            return f.read()

    write(results, RESULTS)
    write(doc, DOC)
    p = run(*files, "--check")
    expect("--check fails on a stale doc", p.returncode == 1, p.stdout + p.stderr)
    expect("--check leaves the doc alone", read(doc) == DOC)

    p = run(*files, "--write")
    expect("--write succeeds", p.returncode == 0, p.stderr)
    expect("--write gives the expected tables", read(doc) == EXPECTED, read(doc))
    p = run(*files, "--check")
    expect("--check passes after --write", p.returncode == 0, p.stdout + p.stderr)
    p = run(*files, "--write")
    expect("--write is idempotent", p.returncode == 0 and read(doc) == EXPECTED, read(doc))

    write(results, RESULTS.replace("\t1.29\t", "\t1.31\t"))
    p = run(*files, "--check")
    expect("--check fails when a figure changes", p.returncode == 1 and "1.31" in p.stdout,
           p.stdout + p.stderr)

    p = run("--results", results)
    expect("without a mode, every part is printed",
           p.returncode == 0 and "## svo" in p.stdout and "## import" in p.stdout, p.stdout + p.stderr)

    write(doc, DOC.replace("<!-- tables:end -->\n\nBetween", "\nBetween", 1))
    p = run(*files, "--check")
    expect("a begin without an end is an error", p.returncode not in (0, 1) and "tables:begin" in p.stderr,
           p.stdout + p.stderr)
    write(doc, DOC.replace("part=import", "part=nothing"))
    p = run(*files, "--check")
    expect("a part without rows is an error", p.returncode not in (0, 1) and "no rows" in p.stderr,
           p.stdout + p.stderr)

print("perf_tables_test: " + ("ok" if failures == 0 else f"{failures} failed"))
sys.exit(1 if failures else 0)
