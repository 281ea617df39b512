#!/usr/bin/env -S /usr/bin/python3
"""Regenerates the key reference in docs/scenes.md from the code (`sphfsi schema`).

usage: /usr/bin/python3 tools/update_scene_docs.py BUILD/bin/sphfsi
The reference sits between the BEGIN/END GENERATED markers; tests/integration/test_docs.py fails when
it differs from what the code declares, so the docs cannot drift.
"""
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOC = os.path.join(ROOT, "docs", "scenes.md")
BEGIN = "<!-- BEGIN GENERATED: sphfsi schema -->"
END = "<!-- END GENERATED -->"


def generated(sphfsi):
    return subprocess.run([sphfsi, "schema"], check=True, capture_output=True, text=True).stdout


def split(text):
    head, rest = text.split(BEGIN, 1)
    body, tail = rest.split(END, 1)
    return head, body, tail


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    with open(DOC) as f:
        head, _, tail = split(f.read())
    text = generated(sys.argv[1])  # before opening the doc for writing: a failure must not empty it
    with open(DOC, "w") as f:
        f.write(head + BEGIN + "\n" + text + "\n" + END + tail)
    print(f"updated {DOC}")
