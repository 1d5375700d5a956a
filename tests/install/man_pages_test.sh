#!/bin/sh
# Every installed program has a manual page that renders without a warning and mentions every
# option its --help lists; so has every subcommand of `selfcal` (selfcal-SUBCOMMAND(1)).
# `cmake --install` into a temporary DESTDIR (prefix /usr), then for each program in usr/bin
# (section 1) and usr/sbin (section 8):
# - usr/share/man/manN/PROGRAM.N.gz exists;
# - `man --warnings -l` renders it without a word on stderr (lintian's check), and lexgrog reads
#   its NAME line ("PROGRAM - summary", what apropos and whatis show);
# - each option (-x, --long-name) on an option line of `PROGRAM --help` is in the page's text.
# Usage: man_pages_test.sh BUILD_DIR
set -eu
build_dir=$1
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
failures=0 checked=0
fail() { echo "FAIL: $*" >&2; failures=$((failures + 1)); }
export LC_ALL=C.UTF-8 MANWIDTH=80

if ! DESTDIR=$work cmake --install "$build_dir" --prefix /usr >"$work/install.log" 2>&1; then
  tail -n 20 "$work/install.log" >&2
  echo "error: cmake --install $build_dir failed" >&2
  exit 1
fi
root=$work/usr

# check_page PAGE COMMAND...: PAGE renders cleanly, has a NAME line, and names every option of
# `COMMAND --help`.
check_page() {
  page=$1
  shift
  checked=$((checked + 1))
  [ -f "$page" ] || { fail "$* has no manual page ($page)"; return; }
  name=$(basename "$page" | sed 's/\.[0-9]\.gz$//')
  if ! man --warnings -E UTF-8 -l -Tutf8 -Z "$page" 2>"$work/warnings" >/dev/null ||
     [ -s "$work/warnings" ]; then
    fail "$name: man --warnings: $(cat "$work/warnings")"
  fi
  lexgrog "$page" 2>&1 | grep -q "\"$name - ." || fail "$name: no NAME line: $(lexgrog "$page" 2>&1)"
  # The page's text: its roff source without font changes and with \- as -, which help2man's
  # pages use for every dash (faster than rendering again; no hyphenation at line ends).
  gzip -dc "$page" | sed 's/\\f[BIRP]//g; s/\\[,\/&]//g; s/\\-/-/g' >"$work/text"
  if ! "$@" --help >"$work/help" 2>&1; then
    fail "$* --help failed: $(head -n 3 "$work/help")"
    return
  fi
  # The options of --help's option lines ("  -c,--config TEXT=...  help"), and every -x or
  # --long-name word in the page: each of the first must be one of the second.
  grep -E '^ +-' "$work/help" | sed 's/^ *//; s/  .*//; s/ [^-].*//' | tr ',' '\n' |
    grep -oE '^ *--?[A-Za-z0-9][A-Za-z0-9-]*' | tr -d ' ' | sort -u >"$work/options"
  [ -s "$work/options" ] || fail "$* --help lists no option (at least --help): the parse is wrong"
  grep -oE -- '(^|[^A-Za-z0-9-])--?[A-Za-z0-9][A-Za-z0-9-]*' "$work/text" |
    sed 's/^[^-]*//' | sort -u >"$work/mentioned"
  for option in $(comm -23 "$work/options" "$work/mentioned"); do
    fail "$name: the page does not mention $option, which $* --help lists"
  done
}

programs=0
for program in "$root"/bin/* "$root"/sbin/*; do
  [ -f "$program" ] || continue
  programs=$((programs + 1))
  case "$program" in */sbin/*) section=8 ;; *) section=1 ;; esac
  name=$(basename "$program")
  check_page "$root/share/man/man$section/$name.$section.gz" "$program"
done
[ "$programs" -gt 0 ] || fail "no program installed under $root/bin or $root/sbin"

# The subcommands of selfcal, as its --help lists them (after "Subcommands:").
if [ -x "$root/bin/selfcal" ]; then
  subcommands=$("$root/bin/selfcal" --help | sed -n '/^Subcommands:/,/^$/p' |
                grep -oE '^  [a-z][a-z0-9-]*' | tr -d ' ')
  [ -n "$subcommands" ] || fail "selfcal --help lists no subcommand"
  for subcommand in $subcommands; do
    check_page "$root/share/man/man1/selfcal-$subcommand.1.gz" "$root/bin/selfcal" "$subcommand"
  done
fi

# No page without its program (a removed program or subcommand leaves none behind).
for page in "$root"/share/man/man*/*.gz; do
  [ -f "$page" ] || continue
  name=$(basename "$page" | sed 's/\.[0-9]\.gz$//')
  [ -e "$root/bin/$name" ] || [ -e "$root/sbin/$name" ] ||
    { [ -x "$root/bin/selfcal" ] && echo "$subcommands" | grep -qx "${name#selfcal-}"; } ||
    fail "$page: no such program or subcommand"
done

# Nothing else under share/man (the wrappers help2man runs for the subcommands stay in the build).
other=$(find "$root/share/man" -mindepth 1 -maxdepth 1 ! -name 'man[0-9]' 2>/dev/null || true)
[ -z "$other" ] || fail "installed under share/man besides the manN folders: $other"

echo "man_pages_test: $checked pages checked, $failures failures"
[ "$failures" -eq 0 ]
