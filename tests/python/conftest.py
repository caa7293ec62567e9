"""Shared fixtures of the Python package tests: the `vibro` program of the same build (the CLI
the package must agree with) and the shipped scenes. ctest passes them as VIBRO_CLI and
VIBRO_SCENES and puts the built package on PYTHONPATH."""
import json
import os
import subprocess

import pytest

CLI = os.environ.get("VIBRO_CLI", "")
SCENES = os.environ.get("VIBRO_SCENES", os.path.join(os.path.dirname(__file__), "..", "..", "data", "scenes"))


def shipped_scenes():
    """Every shipped scene file (the symlinked default.toml is fig08 again: skipped)."""
    return sorted(f for f in os.listdir(SCENES)
                  if f.endswith(".toml") and not os.path.islink(os.path.join(SCENES, f)))


def several_contacts(name):
    """Whether a shipped scene has two or more [[contact]] tables (docs/contacts.md): the exact
    engine only; orbit takes them, check and continue refuse them."""
    import tomllib
    with open(os.path.join(SCENES, name), "rb") as fh:
        return len(tomllib.load(fh).get("contact", [])) > 1


def cli_json(*args):
    """Runs `vibro ARGS --json` and returns its JSON (the CLI must succeed)."""
    if not CLI:
        pytest.fail("VIBRO_CLI is not set: run the tests through ctest")
    p = subprocess.run([CLI, *args, "--json"], capture_output=True, text=True, timeout=600)
    assert p.returncode == 0, p.stderr
    return json.loads(p.stdout)


@pytest.fixture
def scenes_dir():
    return SCENES
