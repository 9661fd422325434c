#!/usr/bin/env bash
# Runs the commands of README.md and docs/*.md, so that they cannot rot (CI: .ci/run).
#
#   tools/check-docs.sh [FILE.md...]        (default: README.md docs/*.md; needs build/)
#
# What runs: the fenced blocks whose opening line is exactly "```sh check" (shell
# commands), "```python check" (a Python script, run as
# `PYTHONPATH=build/python /usr/bin/python3`) or "```cpp check" (a C++ program, built with
# CMake against build/ installed into a scratch prefix, find_package(curvestereo), and
# run). Other blocks (```bash, ```cpp, ...) are for reading: set-up commands that install
# packages, long evaluations on data the repository does not ship, fragments of code. Each file's blocks run in order, in one shell with -e and
# pipefail, as a reader would type them at the repository root; but the root is a fresh
# folder of links to the repository's top-level entries, so that what the commands write
# (scratch/, ...) lands there and is removed afterwards, leaving the checkout untouched.
set -euo pipefail
root=$(cd "$(dirname "$0")/.." && pwd)
cd "$root"
if [ $# -gt 0 ]; then files=("$@"); else files=(README.md docs/*.md); fi
[ -x build/tools/curvestereo ] || { echo "check-docs: build/tools/curvestereo is missing (build first)" >&2; exit 2; }

# The blocks of one file as a bash script.
extract() {
  awk '
    /^```sh check$/ { mode = "sh"; print "# " FILENAME ":" FNR; next }
    /^```python check$/ {
      mode = "py"; print "# " FILENAME ":" FNR
      print "PYTHONPATH=build/python PYTHONDONTWRITEBYTECODE=1 /usr/bin/python3 - <<'"'"'CS_PY_EOF'"'"'"
      next
    }
    /^```cpp check$/ {
      mode = "cpp"; n++; print "# " FILENAME ":" FNR
      print "mkdir -p .cs_cpp" n " && cat > .cs_cpp" n "/main.cpp <<'"'"'CS_CPP_EOF'"'"'"
      next
    }
    /^```/ && mode == "cpp" {
      print "CS_CPP_EOF"
      print "printf '"'"'cmake_minimum_required(VERSION 3.20)\\nproject(example CXX)\\nset(CMAKE_CXX_STANDARD 17)\\nfind_package(curvestereo REQUIRED)\\nadd_executable(example main.cpp)\\ntarget_link_libraries(example PRIVATE curvestereo::curvestereo)\\n'"'"' > .cs_cpp" n "/CMakeLists.txt"
      print "cmake -S .cs_cpp" n " -B .cs_cpp" n "/build -DCMAKE_BUILD_TYPE=Release -DCMAKE_PREFIX_PATH=\"$CS_PREFIX\" >/dev/null"
      print "cmake --build .cs_cpp" n "/build >/dev/null"
      print ".cs_cpp" n "/build/example"
      mode = ""; next
    }
    /^```/ && mode != "" { if (mode == "py") print "CS_PY_EOF"; mode = ""; next }
    mode != "" { print }
  ' "$1"
}

start=$(date +%s)
failed=0
checked=0
for f in "${files[@]}"; do
  script=$(extract "$f")
  [ -n "$script" ] || continue
  work=$(mktemp -d)
  for entry in "$root"/* "$root"/.[!.]*; do
    [ -e "$entry" ] || continue
    case $(basename "$entry") in .git | scratch) continue ;; esac
    ln -s "$entry" "$work/$(basename "$entry")"
  done
  t0=$(date +%s)
  # The C++ examples link the installed package (a copy of build/'s libraries and headers).
  if grep -q '^```cpp check$' "$f"; then cmake --install build --prefix "$work/.prefix" >/dev/null; fi
  if (cd "$work" && export CS_PREFIX="$work/.prefix" && printf 'set -euo pipefail\nset -x\n%s\n' "$script" | bash >"$work/.log" 2>&1); then
    echo "check-docs: $f ok ($(($(date +%s) - t0)) s)"
  else
    echo "check-docs: $f FAILED; the last lines of its output:" >&2
    tail -n 40 "$work/.log" >&2
    failed=1
  fi
  checked=$((checked + 1))
  rm -rf "$work"
done
echo "check-docs: $checked files in $(($(date +%s) - start)) s"
exit $failed
