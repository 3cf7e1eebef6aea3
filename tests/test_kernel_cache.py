"""The compiled kernels' cache is named by the kernels' sources: an edit of any kernel
(a callee compiled into its callers included) starts a fresh cache, an edit elsewhere
does not, and a cache directory the user chose is kept."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from tetherland import kernel_cache
from tetherland.kernel_cache import HASH_LENGTH, cache_dir, kernel_source_hash

CALLEE = "import numba\n\n@numba.njit(cache=True)\ndef mix(x):\n    return x + 1.0\n"
CALLER = (
    "import numba\nfrom pkg.mixer import mix\n\n"
    "@numba.njit(cache=True)\ndef law(x):\n    return 2.0 * mix(x)\n"
)


def _package(tmp_path: Path) -> Path:
    root = tmp_path / "pkg"
    root.mkdir()
    (root / "__init__.py").write_text("")
    (root / "mixer.py").write_text(CALLEE)
    (root / "law.py").write_text(CALLER)
    (root / "docs.py").write_text('"""No compiled code here."""\n')
    return root


def test_an_edit_of_a_callee_alone_changes_the_hash_and_an_edit_elsewhere_does_not(tmp_path):
    root = _package(tmp_path)
    first = kernel_source_hash(root)
    assert len(first) == HASH_LENGTH and first == kernel_source_hash(root)
    (root / "docs.py").write_text('"""Still no compiled code."""\n')
    assert kernel_source_hash(root) == first
    # the caller's file is untouched: numba's own timestamp check would reuse its cache
    (root / "mixer.py").write_text(CALLEE.replace("x + 1.0", "x + 2.0"))
    edited = kernel_source_hash(root)
    assert edited != first
    assert cache_dir(root).name == f"numba-{edited}"
    assert cache_dir(root).parent == root / "__pycache__"  # writable: inside the package


def test_an_edit_of_a_callee_reaches_its_cached_caller(tmp_path):
    """Two fresh processes with the package's cache named by its sources: the caller,
    compiled and cached with the first mixer, returns the edited mixer's value."""
    root = _package(tmp_path)
    script = (
        "import os, sys\n"
        "sys.path.insert(0, sys.argv[1])\n"
        "from pathlib import Path\n"
        "from tetherland.kernel_cache import cache_dir\n"
        "os.environ['NUMBA_CACHE_DIR'] = str(cache_dir(Path(sys.argv[1]) / 'pkg'))\n"
        "from pkg.law import law\n"
        "print(law(1.0))\n"
    )
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}

    def run() -> float:
        out = subprocess.run([sys.executable, "-c", script, str(tmp_path)], env=env,
                             capture_output=True, text=True, check=True)  # fmt: skip
        return float(out.stdout.strip())

    assert run() == 2.0 * (1.0 + 1.0)
    (root / "mixer.py").write_text(CALLEE.replace("x + 1.0", "x + 2.0"))
    assert run() == 2.0 * (1.0 + 2.0)


def test_the_package_sets_the_cache_before_numba_and_keeps_the_users(tmp_path):
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    code = "import os, tetherland; print(os.environ['NUMBA_CACHE_DIR'])"
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True).stdout.strip()  # fmt: skip
    assert out == str(cache_dir())
    assert Path(out).name == f"numba-{kernel_source_hash()}"
    mine = str(tmp_path / "mine")
    out = subprocess.run([sys.executable, "-c", code], env={**env, "NUMBA_CACHE_DIR": mine},
                         capture_output=True, text=True, check=True).stdout.strip()  # fmt: skip
    assert out == mine
    # in this process numba is imported already: configure leaves it alone
    assert "numba" not in sys.modules or kernel_cache.configure() is None
