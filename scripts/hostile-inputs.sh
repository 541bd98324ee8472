#!/usr/bin/env bash
# Runs lodstudio on the hostile inputs of issue 51 and prints, per case, the
# exit code and the one-line message; then exports a folder of hostile glTFs
# beside a good model and scans every file under the output folder for the
# outside secret's bytes. Usage: scripts/hostile-inputs.sh [LODSTUDIO]
set -uo pipefail
BIN="$(realpath "${1:-target/release/lodstudio}")"
W="$(mktemp -d)"; trap 'rm -rf "$W"' EXIT
cd "$W"
SECRET="lodstudio-secret-$(head -c 16 /dev/urandom | od -An -tx1 | tr -d ' \n')"
printf '%s' "$SECRET" > secret.bin
mkdir -p m/sub out
python3 - <<'PY'
import json, struct, base64
tri = struct.pack('<9f', 0,0,0, 1,0,0, 0,1,0)
open('m/sub/tri.bin','wb').write(tri)
def doc(buffer, image=None):
    d = {"asset":{"version":"2.0"},"buffers":[{"uri":buffer,"byteLength":36}],
         "bufferViews":[{"buffer":0,"byteLength":36}],
         "accessors":[{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],
         "meshes":[{"primitives":[{"attributes":{"POSITION":0},"material":0}]}],"materials":[{}],
         "nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}]}
    if image:
        d["images"]=[{"uri":image}]; d["textures"]=[{"source":0}]
        d["materials"][0]["pbrMetallicRoughness"]={"baseColorTexture":{"index":0}}
    return d
import os
secret=os.path.abspath('secret.bin')
cases = {
 "image_etc_passwd": doc("sub/tri.bin", "/etc/passwd"),
 "image_secret_abs": doc("sub/tri.bin", secret),
 "buffer_dotdot": doc("../secret.bin"),
 "buffer_abs": doc(secret),
 "buffer_file_uri": doc("file://"+secret),
 "buffer_symlink": doc("link.bin"),
 "buffer_dev_zero": doc("/dev/zero"),
 "buffer_fifo": doc("fifo.bin"),
 "buffer_folder": doc("sub"),
 "good": doc("sub/tri.bin"),
 "good_data_uri": doc("data:application/octet-stream;base64,"+base64.b64encode(tri).decode()),
}
for k,v in cases.items(): json.dump(v, open(f"m/{k}.gltf","w"))
# A node DAG: 28 levels, each listing the next twice (2^28 instances).
d = doc("sub/tri.bin"); d["nodes"]=[{"mesh":0}]+[{"children":[i-1,i-1]} for i in range(1,28)]
d["scenes"]=[{"nodes":[27]}]; json.dump(d, open("m/dag.gltf","w"))
# An image bomb: a PNG header declaring 60000x60000, named by 60 materials.
png = b"\x89PNG\r\n\x1a\n\x00\x00\x00\x0dIHDR"+struct.pack(">II",60000,60000)+bytes([8,6,0,0,0])
d = doc("sub/tri.bin", "data:image/png;base64,"+base64.b64encode(png).decode())
d["materials"]=[{"pbrMetallicRoughness":{"baseColorTexture":{"index":0}}}]*60
json.dump(d, open("m/bomb.gltf","w"))
json.dump({"format":"lodstudio-recipe","version":1,"rows":[{"method":"simplify","tolerance":"1%"}]*20000}, open("rows.json","w"))
PY
ln -s ../secret.bin m/link.bin; mkfifo m/fifo.bin fifo.obj
python3 -c "
import gzip
with gzip.open('bomb.ply.gz','wb',9) as f:
    f.write(b'ply\nformat binary_little_endian 1.0\nelement vertex 100000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n')
    z=bytes(1<<20)
    for _ in range(2048): f.write(z)
"
run() { local out; out="$(timeout 60 "$BIN" "$@" 2>&1 >/dev/null | tail -1)"; printf '%-4s %-70s %s\n' "$?" "$(echo "$*" | cut -c1-70)" "$out"; }
echo "exit case                                                                   message"
for c in image_etc_passwd image_secret_abs buffer_dotdot buffer_abs buffer_file_uri buffer_symlink buffer_dev_zero buffer_fifo buffer_folder bomb; do
  run export m/$c.gltf --lods simplify:50% -o out/$c.glb
done
run info m/dag.gltf
run info /dev/zero
run info fifo.obj
run info m
run info bomb.ply.gz
run export m/good.gltf --recipe /dev/zero -o out/x.glb
run export m/good.gltf --recipe rows.json -o out/x.glb
run export m/good.gltf --method simplify --lods "$(python3 -c "print(','.join(['1%']*1000))")" -o out/x.glb
run simplify m/good.gltf --ratio 1 -o out/x.glb --save out/x.glb
run export m/good.gltf --lods simplify:50% -o out/b.glb --save-recipe out/b.glb
run measure m/good.gltf m/good.gltf --samples 1000000000000
run amg builtin:octahedron-points --texel 1e-9
run hybrid m/good.gltf --kappa -1 --tau 1
run simplify m/good.gltf --triangles 0 -o out/x.obj
run simplify m/good.gltf --ratio 0 -o out/x.obj
echo "files written by the refused runs: $(find out -type f | wc -l)"
echo "-- hostile batch: export m --lods simplify:50% -o batch --json"
"$BIN" export m --lods simplify:50% -o batch --json > batch.json 2>batch.err; echo "exit $? ($(tail -1 batch.err | cut -c1-160))"
python3 -c "import json; j=json.load(open('batch.json')); print('built', j['built'], 'failed', j['failed'], 'outputs', [o.split('/')[-1] for o in j['outputs']])"
echo "-- scan: grep -rl \"\$SECRET\" batch out (and root:x:0:0 of /etc/passwd)"
hits=$(grep -rla -e "$SECRET" -e "root:x:0:0" batch out | wc -l); echo "files holding an outside file's bytes: $hits"
