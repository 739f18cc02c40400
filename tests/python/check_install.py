"""The package installs from the checkout with Debian's pip, offline, and imports outside the tree.

    check_install.py SOURCE_DIR BUILD_DIR

Copies the package's sources (host_tools/python: setup.py, pyproject.toml, gyrochar/) and the
top CMakeLists.txt (the version) into a temporary folder, so that pip's in-tree build leaves the
checkout untouched; makes a venv with --system-site-packages (numpy from Debian); runs
`pip install --no-build-isolation --no-index` there with GYROCHAR_CMAKE_BUILD_DIR=BUILD_DIR (the
native module built by the project's CMake in that folder); then, from another folder, imports
gyrochar from the venv and checks one analysis against the same call on the build tree's module
(bit for bit: the same code). Run by CTest as python.install.
"""

import pathlib
import shutil
import subprocess
import sys
import tempfile

SCRIPT = """
import json, sys
import numpy as np, gyrochar
assert gyrochar.__file__.startswith(sys.prefix), gyrochar.__file__
x = np.cumsum(np.random.default_rng(1).normal(size=5000))
r = gyrochar.analyze(x, tau0=1.0, stats=("oadev", "mdev"))
print(json.dumps({"file": gyrochar.__file__, "dev": r.oadev.dev.tolist() + r.mdev.dev.tolist()}))
"""


def main(source, build):
    source, build = pathlib.Path(source), pathlib.Path(build)
    with tempfile.TemporaryDirectory(prefix="gyrochar-install-") as tmp:
        tmp = pathlib.Path(tmp)
        package = tmp / "src" / "host_tools" / "python"
        shutil.copytree(source / "host_tools" / "python" / "gyrochar", package / "gyrochar")
        for name in ("setup.py", "pyproject.toml"):
            shutil.copy(source / "host_tools" / "python" / name, package / name)
        shutil.copy(source / "CMakeLists.txt", tmp / "src" / "CMakeLists.txt")
        venv = tmp / "venv"
        made = subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], capture_output=True,
                              text=True)
        if made.returncode != 0 and "ensurepip" in made.stdout + made.stderr:
            print("skipped: venvs get no pip here (Debian package python3-venv):", made.stdout + made.stderr)
            sys.exit(77)
        made.check_returncode()
        python = venv / "bin" / "python"
        env = {"PATH": "/usr/bin:/bin", "GYROCHAR_CMAKE_BUILD_DIR": str(build), "PIP_NO_INDEX": "1",
               "PIP_DISABLE_PIP_VERSION_CHECK": "1", "HOME": str(tmp)}
        subprocess.run([str(python), "-m", "pip", "install", "-q", "--no-build-isolation", str(package)], check=True,
                       env=env)
        work = tmp / "elsewhere"
        work.mkdir()
        installed = subprocess.run([str(python), "-c", SCRIPT], check=True, capture_output=True, text=True, cwd=work,
                                   env={"PATH": "/usr/bin:/bin"}).stdout
        tree = subprocess.run([sys.executable, "-c", SCRIPT.replace("startswith(sys.prefix)", "startswith('/')")],
                              check=True, capture_output=True, text=True, cwd=work,
                              env={"PATH": "/usr/bin:/bin", "PYTHONPATH": str(build / "python")}).stdout
        import json
        a, b = json.loads(installed), json.loads(tree)
        if a["dev"] != b["dev"] or not a["dev"]:
            sys.exit("the installed package's deviations differ from the build tree's")
        print("installed into a venv and imported from", a["file"])


if __name__ == "__main__":
    main(*sys.argv[1:])
