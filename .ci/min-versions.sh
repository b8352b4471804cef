#!/usr/bin/env bash
# Minimum-versions job: prove the lower bounds in pyproject.toml's [project].dependencies.
# Creates a fresh virtual environment at $1, installs the project with its test extra under
# .ci/constraints-min.txt (== pins of each runtime dependency's lowest allowed version), checks the
# pins took, and runs the test suite there. Usage: bash .ci/min-versions.sh VENV_DIR
set -euo pipefail
if [ "$#" -ne 1 ] || [ -z "$1" ]; then
    echo "usage: $0 VENV_DIR (a fresh virtual environment is created there)" >&2
    exit 2
fi
venv="$1"
cd "$(dirname "$0")/.."
constraints=.ci/constraints-min.txt
export MPLBACKEND="${MPLBACKEND:-Agg}"

"${PYTHON:-python3}" -m venv --clear "$venv"
py="$venv/bin/python"
"$py" -m pip install --quiet --disable-pip-version-check -c "$constraints" -e '.[test]'

# every `name==version` line of the constraints file must be what is installed
status=0
while read -r name version; do
    got="$("$py" -c 'import sys
from importlib.metadata import version, PackageNotFoundError
try:
    print(version(sys.argv[1]))
except PackageNotFoundError:
    print("missing")' "$name")"
    if [ "$got" != "$version" ]; then
        echo "min-versions: $constraints pins $name==$version but $venv has $got" >&2
        status=1
    fi
done < <(sed -n 's/^\([A-Za-z0-9_.-]*\)==\([^ #]*\).*/\1 \2/p' "$constraints")
[ "$status" -eq 0 ] || exit 1
echo "min-versions: $(sed -n 's/^\([A-Za-z0-9_.-]*==[^ #]*\).*/\1/p' "$constraints" | tr '\n' ' ')"

"$py" -m pytest -q
