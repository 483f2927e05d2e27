#!/usr/bin/env bash
# Fetch the LAMMPS source tree this package builds against by default:
# the 4 Feb 2025 release as shipped by Debian 13 "trixie" (source package
# lammps, version 20250204+dfsg.1), or the newest one of Debian unstable.
# Only the upstream .orig tarball is used.
#
# The deb-src entry is derived at run time from the machine's own Debian
# sources (no host name is written here), apt runs with a private state
# directory so the system's apt configuration is untouched, and the tarball
# is accepted only if its SHA-256 matches the Sources index.
#
# usage: fetch-lammps.sh CACHE_DIR [stable|newest]   (prints the unpacked tree's path)
#   stable: LAMMPS 4 Feb 2025 (Debian 13), newest: LAMMPS 4 Jul 2026 (Debian unstable)
set -euo pipefail

cache=${1:?usage: fetch-lammps.sh CACHE_DIR [stable|newest]}
release=${2:-stable}
pkg=lammps
case "$release" in
  stable) # Debian 13 "trixie", the default
    suite=trixie version=20250204+dfsg.1 lammps_name="4 Feb 2025" ext=tar.xz ;;
  newest) # Debian unstable
    suite=sid version=20260704+dfsg lammps_name="4 Jul 2026" ext=tar.gz ;;
  *) echo "fetch-lammps: unknown release $release (stable or newest)" >&2; exit 1 ;;
esac
orig="${pkg}_${version}.orig.${ext}"
tree="$cache/lammps-${version}"

if [ -f "$tree/src/lammps.h" ]; then
  echo "$tree"
  exit 0
fi
mkdir -p "$cache"

# first Debian archive URI configured on this machine (deb822 or one-line)
uri=""
for f in /etc/apt/sources.list.d/*.sources; do
  [ -f "$f" ] || continue
  uri=$(awk '/^URIs:/ { for (i = 2; i <= NF; i++) if ($i !~ /security/) { print $i; exit } }' "$f")
  [ -n "$uri" ] && break
done
if [ -z "$uri" ]; then
  uri=$(cat /etc/apt/sources.list /etc/apt/sources.list.d/*.list 2>/dev/null |
    awk '$1 == "deb" && $0 !~ /security/ { for (i = 2; i <= NF; i++) if ($i ~ /:\/\//) { print $i; exit } }')
fi
[ -n "$uri" ] || { echo "fetch-lammps: no Debian archive found in the apt sources" >&2; exit 1; }

state=$(mktemp -d "$cache/apt-state.XXXXXX")
trap 'rm -rf "$state"' EXIT
mkdir -p "$state/lists/partial" "$state/archives/partial" "$state/etc/preferences.d"
echo "deb-src $uri $suite main" > "$state/etc/sources.list"
apt_opts=(-o "Dir::State=$state" -o "Dir::State::Lists=$state/lists"
  -o "Dir::Cache=$state" -o "Dir::Cache::Archives=$state/archives"
  -o "Dir::Etc::SourceList=$state/etc/sources.list" -o "Dir::Etc::SourceParts=/dev/null"
  -o "Dir::Etc::Preferences=$state/etc/preferences" -o "Dir::Etc::PreferencesParts=$state/etc/preferences.d"
  -o "APT::Sandbox::User=root" -o "Debug::NoLocking=1")

apt-get "${apt_opts[@]}" -qq update >&2

sources=$(ls "$state"/lists/*_source_Sources* 2>/dev/null | head -n 1)
[ -n "$sources" ] || { echo "fetch-lammps: no Sources index for $suite" >&2; exit 1; }
# the index may be stored compressed; apt-helper reads every format apt writes
/usr/lib/apt/apt-helper cat-file "$sources" > "$state/Sources"
# version, SHA-256 and pool folder of the tarball (Directory: follows the
# checksums within the package's stanza)
read -r debver expected directory < <(awk -v p="$pkg" -v v="$version" -v f="$orig" '
  /^$/ { if (sha != "") exit; cur = "" }
  /^Package:/ { cur = $2 } /^Version:/ { ver = $2 }
  /^Checksums-Sha256:/ { in_sha = 1; next } /^[^ ]/ { in_sha = 0 }
  in_sha && cur == p && index(ver, v) == 1 && $3 == f { sha = $1; found = ver }
  /^Directory:/ && sha != "" && dir == "" { dir = $2 }
  END { if (sha != "" && dir != "") print found, sha, dir }' "$state/Sources") || true
[ -n "${directory:-}" ] || { echo "fetch-lammps: $orig not listed in the Sources index" >&2; exit 1; }

# only the tarball is fetched, by apt's own downloader, which also checks
# the SHA-256; its progress lines stay in a log
if ! /usr/lib/apt/apt-helper "${apt_opts[@]}" download-file "$uri/$directory/$orig" \
  "$state/$orig" "SHA256:$expected" > "$state/download.log" 2>&1; then
  echo "fetch-lammps: download of $orig failed:" >&2
  grep -E "^(E|W):" "$state/download.log" | sed 's/http[^ ]*//g' >&2
  exit 1
fi
actual=$(sha256sum "$state/$orig" | cut -d' ' -f1)
if [ "$actual" != "$expected" ]; then
  echo "fetch-lammps: SHA-256 mismatch for $orig ($actual, expected $expected)" >&2
  exit 1
fi
echo "fetch-lammps: LAMMPS ${lammps_name} (Debian source package $pkg $debver), SHA-256 verified" >&2

unpack=$(mktemp -d "$cache/unpack.XXXXXX")
tar -xf "$state/$orig" -C "$unpack"
# the tarball holds the tree itself or one folder with it
top=$unpack
[ -f "$top/src/lammps.h" ] || top=$(find "$unpack" -mindepth 1 -maxdepth 1 -type d | head -n 1)
[ -f "$top/src/lammps.h" ] || { rm -rf "$unpack"; echo "fetch-lammps: unexpected tarball layout" >&2; exit 1; }
mv "$top" "$tree"
rm -rf "$unpack"
echo "$tree"
