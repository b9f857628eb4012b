"""Shared fixtures of the Python tests: the data set, the built tools, scratch folders.

ctest sets PYTHONPATH (the build tree's package), WEIGHTED_ICP_TOOLS_DIR and WEIGHTED_ICP_DATA_DIR
(python_bindings_stub/CMakeLists.txt). Tests that need the data skip, saying why, only where it is absent.
"""

import json
import os
import subprocess
from pathlib import Path
from typing import Any, Dict, List

import pytest

DATA_DIR = Path(os.environ.get("WEIGHTED_ICP_DATA_DIR", Path(__file__).resolve().parents[2] / ".." / "shared" / "data"))
TOOLS_DIR = Path(os.environ.get("WEIGHTED_ICP_TOOLS_DIR", Path(__file__).resolve().parents[2] / "build" / "examples"))


@pytest.fixture(scope="session")
def real_map_path() -> Path:
    """The real landmark map; the test skips when the data set is absent."""
    path = DATA_DIR / "map_fr1_desk.txt"
    if not path.exists():
        pytest.skip(f"the shared data set is absent ({path})")
    return path


@pytest.fixture(scope="session")
def tum_folder() -> Path:
    """The TUM fr1/xyz head sequence; the test skips when it is absent."""
    path = DATA_DIR / "tum_fr1_xyz_head"
    if not (path / "rgb.txt").exists():
        pytest.skip(f"the shared data set is absent ({path})")
    return path


def run_tool(name: str, *args: str) -> Dict[str, Any]:
    """Runs a built tool with --json and returns its JSON line; fails the test on a crash."""
    tool = TOOLS_DIR / name
    if not tool.exists():
        pytest.fail(f"{tool} is not built (ninja -C build {name})")
    done = subprocess.run([str(tool), *args, "--json"], capture_output=True, text=True, timeout=300)
    assert done.returncode in (0, 3), f"{name} exit {done.returncode}: {done.stderr}"
    lines: List[str] = done.stdout.strip().splitlines()
    result: Dict[str, Any] = json.loads(lines[-1])
    return result
