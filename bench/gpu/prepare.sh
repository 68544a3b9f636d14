#!/usr/bin/env bash
# Here (no GPU needed), before the device calls: the warp-lang wheel for the lent GPU
# machine's Python 3.12, in parts that each fit one call's 64 MiB carry (the wheel is
# 142 MiB), with its checksum. Writes .whl/ at the repository root, ignored by git.
set -euo pipefail
cd "$(dirname "$0")/../.."
WARP=1.19.0
grep -qx '/.whl/' .git/info/exclude || echo '/.whl/' >> .git/info/exclude
rm -rf .whl && mkdir -p .whl/dl
python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 \
    --implementation cp --platform manylinux_2_28_x86_64 -d .whl/dl "warp-lang==$WARP"
wheel=$(ls .whl/dl/warp_lang-"$WARP"-*.whl)
basename "$wheel" > .whl/wheel.name
sha256sum "$wheel" | cut -d' ' -f1 > .whl/wheel.sha256
split -b 48M -d "$wheel" .whl/wheel.part
rm -r .whl/dl
ls -l .whl
