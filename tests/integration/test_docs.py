"""docs/scenes.md carries the key reference generated from the code: this fails when they differ
(regenerate with tools/update_scene_docs.py)."""
import os
import sys

import harness

sys.path.insert(0, os.path.join(harness.ROOT, "tools"))
import update_scene_docs  # noqa: E402


def test_scene_reference_matches_the_code():
    with open(update_scene_docs.DOC) as f:
        _, body, _ = update_scene_docs.split(f.read())
    want = update_scene_docs.generated(os.path.join(harness.BIN, "sphfsi"))
    assert body.strip() == want.strip(), "docs/scenes.md is stale: run /usr/bin/python3 tools/update_scene_docs.py build/bin/sphfsi"


if __name__ == "__main__":
    harness.main(globals())
