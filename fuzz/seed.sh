#!/bin/sh
# Fills corpus/<target>/ with seeds: the repository's assets and scenes, the test models in
# ../shared/data (beside the repository), small PLY files, and an impostor baked by trompe.
set -eu
here=$(cd "$(dirname "$0")" && pwd)
repo=$(dirname "$here")
data="$repo/../shared/data"
for t in obj ply gltf hdr exr scene maze impostor colmap; do mkdir -p "$here/corpus/$t"; done
c="$here/corpus"

# OBJ seeds: meshes under 400 KB, then an OBJ with its MTL after the marker.
for f in "$repo/assets/meshes/teapot.obj" "$data/meshes/bunny_lowres.obj" "$data/meshes/dragon_res4.obj"; do
    [ -f "$f" ] && cp "$f" "$c/obj/$(basename "$f")"
done
if [ -f "$data/meshes/bunny10k_textured/bunny10k_textured.obj" ]; then
    d="$data/meshes/bunny10k_textured"
    { head -c 60000 "$d/bunny10k_textured.obj"; printf '\n--8<--\n'; cat "$d"/*.mtl; } > "$c/obj/textured"
fi
printf 'mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\nusemtl a\nf 1/1/1 2/2/1 3/3/1\n\n--8<--\nnewmtl a\nKd 0.8 0.2 0.1\n' > "$c/obj/triangle"

# PLY seeds, ASCII and binary.
python3 - "$c/ply" <<'PY'
import struct, sys, os
out = sys.argv[1]
head = lambda fmt, extra="": (f"ply\nformat {fmt} 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
    f"property float z\n{extra}element face 2\nproperty list uchar int vertex_indices\nend_header\n").encode()
v = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (1, 1, 0)]
f = [(0, 1, 2), (1, 3, 2)]
open(os.path.join(out, "ascii.ply"), "wb").write(head("ascii") + b"".join(
    (" ".join(map(str, p)) + "\n").encode() for p in v) + b"".join(f"3 {a} {b} {c}\n".encode() for a, b, c in f))
for name, e in (("le.ply", "<"), ("be.ply", ">")):
    fmt = "binary_little_endian" if e == "<" else "binary_big_endian"
    body = b"".join(struct.pack(e + "3f", *p) for p in v) + b"".join(struct.pack(e + "B3i", 3, *t) for t in f)
    open(os.path.join(out, name), "wb").write(head(fmt) + body)
PY

# glTF, panoramas, scenes, mazes.
for f in "$data"/gltf/*.glb "$repo"/assets/gltf/*.glb; do [ -f "$f" ] && cp "$f" "$c/gltf/"; done
[ -f "$data/gltf/CesiumMilkTruck/CesiumMilkTruck.gltf" ] && cp "$data/gltf/CesiumMilkTruck/CesiumMilkTruck.gltf" "$c/gltf/"
for f in "$data"/envmaps/studio.hdr "$repo"/assets/envmaps/studio.hdr; do [ -f "$f" ] && cp "$f" "$c/hdr/$(basename "$f")"; done
cp "$repo"/assets/envmaps/*.exr "$c/exr/"
# Scene seeds name the small teapot for every mesh and (but one) no panorama, so each run
# loads in milliseconds.
for f in "$repo"/scenes/*.toml; do
    sed -e 's#meshes/bunny\.obj#meshes/teapot.obj#g' -e '/^path = .*envmaps/d' "$f" \
        > "$c/scene/$(basename "$f")"
done
sed 's#meshes/bunny\.obj#meshes/teapot.obj#g' "$repo/scenes/turntable.toml" > "$c/scene/panorama.toml"
cp "$repo"/scenes/*.maze "$c/maze/"

# COLMAP models written by COLMAP itself (the test fixtures).
f="$repo/tests/fixtures/colmap"
for kind in text:txt binary:bin; do
    dir=${kind%%:*}; ext=${kind##*:}
    { cat "$f/$dir/cameras.$ext"; printf '\n--8<--\n'; cat "$f/$dir/images.$ext"; } > "$c/colmap/$dir"
done

# An impostor: a small bake, its sidecar and EXR joined by the marker.
tmp=$(mktemp -d)
(cd "$repo" && cargo run --release --quiet -- impostor bake assets/meshes/teapot.obj --resolution 32 -o "$tmp/i.json")
sed 's/"exr": "[^"]*"/"exr": "i.exr"/' "$tmp/i.json" > "$tmp/s.json"
{ cat "$tmp/s.json"; printf '\n--8<--\n'; cat "$tmp/i.exr"; } > "$c/impostor/teapot32"
cp "$tmp/i.exr" "$c/exr/impostor32.exr"
rm -rf "$tmp"
echo "seeds in $c:"; for t in "$c"/*; do echo "  $(basename "$t"): $(ls "$t" | wc -l)"; done
