#!/usr/bin/python3
"""The README's examples say what the tools print: runs each one and compares.

- A fenced block whose first line is `$ build/apps/TOOL ARGS` (a trailing `# excerpt` comment and
  `2>/dev/null` allowed) runs the command; every later line of the block must be a line of its
  stdout, in order (an excerpt skips lines), a line ending in `...` a prefix of one.
- A sentence "`svo-voxelize ARGS` finds N voxels" runs the command and compares the voxel count of
  its --json report; "`svo-build ARGS` prints ... the file is N bytes" compares the file's size.
Paths out/demo/ become a scratch folder, build/apps/ the tools' folder (SVOKIT_BIN_DIR); the
commands run from the repository root, in README order, as scripts/demo runs them.
"""
import json
import os
import re
import shlex
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BIN = os.environ.get("SVOKIT_BIN_DIR", os.path.join(ROOT, "build", "apps"))


def command(text, out):
    text = re.sub(r"\s+#.*$", "", text.strip())
    words = [w for w in shlex.split(text) if w not in ("2>/dev/null",)]
    if words[0].startswith("build/apps/"):
        words[0] = words[0][len("build/apps/"):]
    words[0] = os.path.join(BIN, words[0])
    return [w.replace("out/demo", out) for w in words]


def run(words):
    done = subprocess.run(words, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True)
    if done.returncode != 0:
        sys.exit("FAIL: %s exited %d: %s" % (" ".join(words), done.returncode, done.stderr))
    return done.stdout


def check_block(lines, out):
    words = command(lines[0][2:], out)
    printed = run(words).splitlines()
    at = 0
    for want in lines[1:]:
        prefix = want.endswith("...")
        key = want[:-3].rstrip() if prefix else want
        while at < len(printed) and not (printed[at].startswith(key) if prefix
                                         else printed[at] == key):
            at += 1
        if at == len(printed):
            sys.exit("FAIL: README shows %r for `%s`; it printed:\n%s"
                     % (want, lines[0], "\n".join(printed)))
        at += 1
    return 1


def main():
    readme = open(os.path.join(ROOT, "README.md"), encoding="utf-8").read()
    checked = 0
    with tempfile.TemporaryDirectory() as out:
        # Blocks and sentences in README order: later commands read earlier outputs.
        items = []
        for m in re.finditer(r"```\n(\$ build/apps/[^\n]*\n(?:.*\n)*?)```", readme):
            items.append((m.start(), "block", m.group(1).rstrip("\n").split("\n")))
        for m in re.finditer(r"`(svo-voxelize [^`]*)` finds (\d+) voxels", readme):
            items.append((m.start(), "voxels", (m.group(1), int(m.group(2)))))
        for m in re.finditer(r"`(svo-build [^`]*)` prints[^`]*?the file is (\d+) bytes", readme):
            items.append((m.start(), "bytes", (m.group(1), int(m.group(2)))))
        for _, kind, item in sorted(items, key=lambda i: i[0]):
            if kind == "block":
                checked += check_block(item, out)
            elif kind == "voxels":
                report = json.loads(run(command(item[0], out) + ["--json", "-q"]))
                got = report["voxels"]["count"] if isinstance(report["voxels"], dict) \
                    else report["voxels"]
                if got != item[1]:
                    sys.exit("FAIL: README says `%s` finds %d voxels; it finds %d"
                             % (item[0], item[1], got))
                checked += 1
            else:
                words = command(item[0], out)
                run(words + ["-q"])
                path = words[words.index("-o") + 1]
                if os.path.getsize(path) != item[1]:
                    sys.exit("FAIL: README says `%s` writes %d bytes; it wrote %d"
                             % (item[0], item[1], os.path.getsize(path)))
                checked += 1
    if checked < 4:
        sys.exit("FAIL: found only %d README examples to check" % checked)
    print("%d README examples match" % checked)


if __name__ == "__main__":
    main()
