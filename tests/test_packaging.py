"""The bundled robots ship inside a built wheel (not only in an editable checkout)."""

import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from evoik_pin.robot import BUNDLED_ROBOTS

ROOT = Path(__file__).resolve().parents[1]


def test_wheel_contains_bundled_robots(tmp_path):
    pytest.importorskip("hatchling", reason="hatchling (a dev extra) builds the wheel offline")
    proc = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w", str(tmp_path),
         str(ROOT)],
        capture_output=True, text=True, timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    wheels = list(tmp_path.glob("evoik_pin-*.whl"))
    assert len(wheels) == 1
    names = set(zipfile.ZipFile(wheels[0]).namelist())
    for robot in BUNDLED_ROBOTS:
        assert f"evoik_pin/robots/{robot}.urdf" in names
    for module in ("__init__", "loading", "robot", "frames"):
        assert f"evoik_pin/robot/{module}.py" in names
    for package in ("goals", "io", "papers", "motion"):
        assert f"evoik_pin/{package}/__init__.py" in names


def test_installed_wheel_loads_bundled_robots(tmp_path):
    pytest.importorskip("hatchling", reason="hatchling (a dev extra) builds the wheel offline")
    subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w",
                    str(tmp_path), str(ROOT)], check=True, capture_output=True, timeout=300)
    site = tmp_path / "site"
    wheel = next(tmp_path.glob("evoik_pin-*.whl"))
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target", str(site), str(wheel)],
                   check=True, capture_output=True, timeout=300)
    code = ("import evoik_pin, sys; from evoik_pin.robot import bundled_robots_dir; "
            "r = evoik_pin.load_robot('puma3r'); print(evoik_pin.__file__); print(bundled_robots_dir())")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                          env={"PYTHONPATH": str(site), "PATH": "/usr/bin:/bin"}, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    module_file, robots_dir = proc.stdout.split()
    assert module_file.startswith(str(site)) and robots_dir.startswith(str(site))
    assert Path(robots_dir) == Path(module_file).parent / "robots"  # evoik_pin/robots, found from evoik_pin/robot/
