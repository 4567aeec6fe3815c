"""The documented install: `cmake --install <build> --component python --prefix <venv>` (docs/python.md)."""
import os
import pathlib
import subprocess
import sys

import pytest

BUILD_DIR = os.environ.get("QUIJIBO_BUILD_DIR")


@pytest.mark.skipif(not BUILD_DIR, reason="QUIJIBO_BUILD_DIR is not set (ctest sets it)")
def test_install_into_a_virtual_environment(tmp_path):
    venv = tmp_path / "venv"
    # --system-site-packages: Debian's NumPy; --without-pip: nothing to download.
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", "--without-pip", str(venv)], check=True)
    subprocess.run(["cmake", "--install", BUILD_DIR, "--component", "python", "--prefix", str(venv)], check=True,
                   capture_output=True)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    code = "import quijibo, sys; print(quijibo.__file__); print(quijibo.random_map(top=2, bottom=1).top_count)"
    p = subprocess.run([str(venv / "bin" / "python"), "-c", code], capture_output=True, text=True, env=env,
                       cwd=tmp_path, check=True)
    where, count = p.stdout.split()
    assert pathlib.Path(where).is_relative_to(venv) and count == "2"
