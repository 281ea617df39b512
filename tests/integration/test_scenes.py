"""Scene validation: every mistake is named with the file, the line, the key and the allowed values,
and nothing runs on an invalid scene (no output directory is created)."""
import os

import harness

INVALID = os.path.join(harness.SCENES, "invalid")


def test_every_mistake_is_named():
    path = os.path.join(INVALID, "many_mistakes.toml")
    code, text = harness.sphfsi("check", path)
    assert code == 2, text
    for expected in [
        f"{path}: line 3: key 'run.end_time': got -1; allowed: a number > 0 and <= 1e+06 (s)",
        f"{path}: line 4: key 'run.timeout_s': got a string; allowed: a number > 0 and <= 3600 (s)",
        f"{path}: line 5: unknown key 'run.colour'; allowed keys here: \"title\", \"end_time\"",
        f"{path}: line 8: key 'load.force': got 1 entries; allowed: an array of 2 numbers (N/m)",
    ]:
        assert expected in text, f"missing: {expected}\n---\n{text}"


def test_invalid_toml_names_the_line():
    path = os.path.join(INVALID, "not_toml.toml")
    code, text = harness.sphfsi("check", path)
    assert code == 2 and f"{path}:3: not valid TOML" in text, text


def test_a_scene_needs_a_participant():
    code, text = harness.sphfsi("check", os.path.join(INVALID, "empty_scene.toml"))
    assert code == 2 and "the scene has neither [fluid] nor [structure]" in text, text


def test_bad_override_is_named():
    scene = os.path.join(harness.SCENES, "rigid_plate_step.toml")
    code, text = harness.sphfsi("check", scene, "--set", "run.end_tme=3")
    assert code == 2 and "unknown key 'run.end_tme'" in text, text
    code, text = harness.sphfsi("check", scene, "--set", "run.output_interval=0")
    assert code == 2 and "key 'run.output_interval': got 0" in text, text
    # A typo such as 1e-300 for 1e-3 would crawl while filling the disk: at most a million frames.
    code, text = harness.sphfsi("check", scene, "--set", "run.output_interval=1e-300")
    assert code == 2 and "key 'run.output_interval': must be at least run.end_time / 1e6" in text, text
    # A number TOML cannot hold is a mistake, not the bare word "1e400" (which the schema called a string).
    code, text = harness.sphfsi("check", scene, "--set", "run.end_time=1e400")
    assert code == 2 and "--set run.end_time=1e400: the value is not valid TOML" in text, text
    code, text = harness.sphfsi("check", scene, "--set", "load.force=[0.0, -200.0")
    assert code == 2 and "the value is not valid TOML" in text, text


def test_a_known_unstable_choice_is_valid_but_warned_about():
    """The thesis's kernel pair with summed densities grows at rest (docs/validation.md, "The thesis's kernel
    pair at rest"): the scene stays valid, as the issue asks for the pair, and check says so; the same pair
    with continuity densities, and the default kernel with summed densities, are stable and not warned about."""
    scene = os.path.join(harness.ROOT, "scenarios", "dam_break.toml")
    code, text = harness.sphfsi("check", scene, "--set", "fluid.kernel=mueller", "--set", "fluid.density.method=summation")
    assert code == 0 and 'warning: fluid.kernel = "mueller" with summed densities' in text, text
    for sets in (["fluid.kernel=mueller"], ["fluid.density.method=summation"],
                 ["fluid.kernel=mueller", "fluid.density.method=summation", "fluid.h_over_dp=1.0"]):
        args = [a for s in sets for a in ("--set", s)]
        code, text = harness.sphfsi("check", scene, *args)
        assert code == 0 and "warning" not in text, (sets, text)


def test_nothing_runs_on_an_invalid_scene():
    out = os.path.join(harness.out_dir("invalid"), "never")
    code, text = harness.sphfsi("run", os.path.join(INVALID, "many_mistakes.toml"), "--out", out)
    assert code == 2, text
    assert not os.path.exists(out), "an output directory was created for an invalid scene"


def test_missing_file_is_named():
    code, text = harness.sphfsi("check", "/nonexistent/scene.toml")
    assert code == 2 and "/nonexistent/scene.toml: cannot read the scene file" in text, text
    code, text = harness.sphfsi("check", harness.SCENES)
    assert code == 2 and "is a directory, not a scene file" in text, text


if __name__ == "__main__":
    harness.main(globals())
