#!/usr/bin/env python3
"""ctest's entry to the Python tests: runs pytest on this folder with the interpreter the
module was built for, or exits 77 (ctest: skipped) saying what is missing."""
import importlib.util
import sys
import tempfile

missing = [m for m in ("pytest", "numpy") if importlib.util.find_spec(m) is None]
if missing:
    print(
        f"python_tests skipped: {' and '.join(missing)} not installed for {sys.executable} "
        "(Debian: apt-get install python3-pytest python3-numpy)"
    )
    sys.exit(77)

sys.dont_write_bytecode = True  # no __pycache__ beside the tests
import pytest  # noqa: E402

# No cache folder in the source tree, and the tests' temporary folders (tmp_path) in one
# folder removed afterwards (pytest would keep its last three runs' in the temp folder);
# -rs lists why tests were skipped (e.g. no GPU).
with tempfile.TemporaryDirectory(prefix="curvestereo_pytest_") as base:
    code = pytest.main(["-q", "-rs", "-p", "no:cacheprovider", f"--basetemp={base}", *sys.argv[1:]])
sys.exit(code)
