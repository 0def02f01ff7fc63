#!/usr/bin/env bash
# The wheels a lent many-core device lacks (benchmarks/README.md, "Many-core figures on a lent
# device"), into CHECKOUT/.whl: run here, where the registry is, with the project's venv
# active (its installed versions are the ones carried: benchmarks/device_deps.py).
#
#     benchmarks/device_wheels.sh [CHECKOUT]   # default: the checkout of the current directory
#
# CHECKOUT is the one the device receives (the session's own). One wheel a package,
# --no-deps, for CPython 3.12 on manylinux x86-64 or pure Python (py3-none-any); .whl/ is
# emptied first and kept out of git (.git/info/exclude). Prints each wheel, their total and
# the tree's size: with .whl carried, at most 64 MiB travel.
set -euo pipefail
here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
checkout=$(git -C "${1:-$PWD}" rev-parse --show-toplevel)
python=${PYTHON:-python3}
dest=$checkout/.whl

exclude=$(git -C "$checkout" rev-parse --path-format=absolute --git-path info/exclude)
mkdir -p "$(dirname "$exclude")"
grep -qxF /.whl/ "$exclude" 2>/dev/null || echo /.whl/ >>"$exclude"

pins=$("$python" "$here/device_deps.py" wheels)
rm -rf "$dest"
mkdir -p "$dest"
binary=(--no-deps --only-binary=:all: --python-version 3.12 --implementation cp)
for tag in manylinux_2_28 manylinux_2_27 manylinux_2_17 manylinux2014 manylinux1; do
    binary+=(--platform "${tag}_x86_64")
done
# shellcheck disable=SC2086 # one argument a pin
"$python" -m pip download -q "${binary[@]}" -d "$dest" $pins

wheels=("$dest"/*.whl)
if [ "${#wheels[@]}" -ne "$(wc -w <<<"$pins")" ]; then
    echo "expected one wheel for each of: $pins" >&2
    exit 1
fi
stat -c '%s %n' "${wheels[@]}" | awk '{n = split($2, p, "/"); printf "%6.2f MB  %s\n", $1 / 1e6, p[n]}'
tree=$(git -C "$checkout" ls-files -z --cached --others --exclude-standard |
    (cd "$checkout" && du -cb --files0-from=- 2>/dev/null | tail -1 | cut -f1))
whl=$(du -cb "${wheels[@]}" | tail -1 | cut -f1)
awk -v t="$tree" -v w="$whl" -v n="${#wheels[@]}" 'BEGIN {
    printf "%d wheels, %.1f MiB; the tree %.1f MiB; together %.1f MiB of 64\n",
        n, w / 2^20, t / 2^20, (t + w) / 2^20
    exit (t + w > 64 * 2^20)
}'
