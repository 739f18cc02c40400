#!/usr/bin/env bash
# The project's C++ sources in the style of .clang-format (clang-format 14, Debian's clang-format).
#   toolchain/format.sh           formats them in place
#   toolchain/format.sh --check   changes nothing; lists the files that need formatting and exits 1
#                                 if there are any (0 when all are formatted)
# The sources: the C++ files git tracks under core/, hal/, firmware/, host_tools/ and tests/
# (never a build folder). A region the style would spoil is kept as written between
# `// clang-format off` and `// clang-format on`.
set -euo pipefail
cd "$(dirname "$0")/.."

check=0
case "${1:-}" in
  "") ;;
  --check) check=1 ;;
  *) echo "usage: toolchain/format.sh [--check]" >&2; exit 2 ;;
esac
clang_format=${CLANG_FORMAT:-clang-format}
if ! command -v "$clang_format" >/dev/null; then
  echo "format.sh: $clang_format not found (Debian package clang-format; toolchain/build.sh test installs it)" >&2
  exit 2
fi

mapfile -t files < <(git ls-files -- core hal firmware host_tools tests | grep -E '\.(cpp|hpp|h|c)$')
if ((check == 0)); then
  printf '%s\0' "${files[@]}" | xargs -0 -n 32 "$clang_format" -i --style=file
  exit 0
fi
# One clang-format a file (its exit status says whether that file is formatted), on every core.
mapfile -t unformatted < <(printf '%s\0' "${files[@]}" | xargs -0 -P "$(nproc)" -I{} \
  sh -c '"$0" --style=file --dry-run --Werror "$1" >/dev/null 2>&1 || echo "$1"' "$clang_format" {} | sort)
if ((${#unformatted[@]})); then
  echo "format.sh: ${#unformatted[@]} of ${#files[@]} files need formatting (toolchain/format.sh formats them):" >&2
  printf '  %s\n' "${unformatted[@]}" >&2
  exit 1
fi
echo "format.sh: all ${#files[@]} files formatted" >&2
