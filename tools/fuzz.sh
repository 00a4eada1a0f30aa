#!/usr/bin/env bash
# Fuzzes what relume reads (cargo fuzz, libFuzzer; docs/RELIABILITY.md): the glTF/GLB loader,
# the bake artifact's manifest and every method's sections, the EXR and PNG readers, sweep
# files, lights files and viewer scripts, each for a fixed number of runs (or minutes) from
# seed corpora made of the shipped scenes, images, sweeps and fresh bakes and lights files.
# Not part of the test command: it needs the nightly toolchain and takes minutes. A crash
# stops the script and leaves its input in fuzz/artifacts/<target>/.
#
#   bash tools/fuzz.sh [RUNS]              (default 20000 runs per target)
#   bash tools/fuzz.sh --minutes M [TARGET...]   (M minutes per target; default every target)
set -euo pipefail
cd "$(dirname "$0")/.."
TARGETS=(gltf artifact image sweep lights script)
if [[ "${1:-}" == "--minutes" ]]; then
    LIMIT=(-max_total_time=$(( ${2:?give the minutes} * 60 )))
    DESCRIBED="${2} minutes"
    shift 2
    [[ $# -gt 0 ]] && TARGETS=("$@")
else
    LIMIT=(-runs="${1:-20000}")
    DESCRIBED="${1:-20000} runs"
fi
if ! rustup toolchain list | grep -q '^nightly'; then
    echo "fuzz.sh: cargo fuzz needs the nightly toolchain: rustup toolchain install nightly" >&2
    exit 1
fi
if ! cargo fuzz --version >/dev/null 2>&1; then
    echo "installing cargo-fuzz"
    cargo install cargo-fuzz --locked
fi

corpus=target/fuzz-corpus
rm -rf "$corpus"
mkdir -p "$corpus"/{gltf,artifact,image,sweep,lights,script}

echo "seeds: the shipped scenes, environments and sweeps"
cp scenes/*.gltf "$corpus/gltf/"
for exr in scenes/envs/*.exr; do
    { printf '\x00'; cat "$exr"; } > "$corpus/image/$(basename "$exr")"
done
for sweep in tools/sweeps/*.toml; do cp "$sweep" "$corpus/sweep/"; done
printf 'overlay off\nframes 2\nmethod obscurance\nlight 0 position 0.1 1.2 0.3\nlight 0 intensity 3 2.5 2\nlight 0 cone 20 30\nsize 64 48\norbit 10 -5\nreference 4\nidle 100\nscreenshot s.png\nsave-lights l.json\nquit\n' > "$corpus/script/session.txt"

echo "seeds: small bakes of cornell (obscurance, light path maps), fiv-blobs (fiv), cornell-cloud (light-cloud) and mrt-cube (mrt), and a PNG"
cargo build --release --locked -p relume-tools
relume=target/release/relume
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$relume" bake scenes/cornell.gltf --method obscurance --patches 2000 --rays 16 --out "$work/obscurance" >/dev/null
"$relume" bake scenes/cornell.gltf --method light-path-maps --patches 2000 --rays 16 --entry-points 256 --clusters 4 --basis 2 --out "$work/lpm" >/dev/null
"$relume" bake scenes/fiv-blobs.gltf --method fiv --grid 32x17x15 --difmap-width 16 --out "$work/fiv" >/dev/null
"$relume" bake scenes/cornell-cloud.gltf --method light-cloud --samples 1 --clusters 4 --vectors 2 --out "$work/lc" >/dev/null
"$relume" bake scenes/mrt-cube.gltf --method mrt --samples-per-face 4 --gather-rays 64 --modes 4 --prior-modes 8 --lightfield 2 --lightfield-modes 4 --response-modes 4 --dictionary-cache "$work/kept" --out "$work/mrt" >/dev/null
"$relume" reference scenes/cornell.gltf --width 16 --height 16 --spp 1 --out "$work/small.exr" >/dev/null
{ printf '\x01'; cat "$work/small.png"; } > "$corpus/image/small.png"
for scene in cornell classroom courtyard; do "$relume" lights "scenes/$scene.gltf" --out "$corpus/lights/$scene.json" 2>/dev/null; done
python3 - "$work" "$corpus/artifact" <<'PY'
import json, struct, sys, os
work, out = sys.argv[1], sys.argv[2]
def seed(name, selector, payload):
    open(os.path.join(out, name), 'wb').write(bytes([selector]) + payload)
def read(*parts):
    return open(os.path.join(work, *parts), 'rb').read()
def layout(bake):
    manifest = json.load(open(os.path.join(work, bake, 'manifest.json')))
    atlas = next(s for s in manifest['sections'] if s['name'] == 'atlas')['summary']
    width, height = atlas['width'], atlas['height'] * atlas['pages']
    return struct.pack('<HH', width, height)
seed('manifest', 0, read('obscurance', 'manifest.json'))
seed('atlas', 1, read('obscurance', 'atlas.bin'))
seed('obscurance', 2, layout('obscurance') + read('obscurance', 'obscurance.exr'))
seed('light-path-maps', 3, layout('lpm') + read('lpm', 'light-path-maps.bin'))
environment = read('fiv', 'fiv_environment.bin')
seed('fiv-environment', 4, environment)
seed('fiv-table', 5, struct.pack('<I', len(environment)) + environment + read('fiv', 'fiv_occluder_0.bin'))
seed('light-cloud', 6, read('lc', 'light-cloud.bin'))
dictionary = read('mrt', 'mrt-dictionary.bin')
seed('mrt-dictionary', 7, dictionary)
seed('mrt-level', 8, struct.pack('<I', len(dictionary)) + dictionary + read('mrt', 'mrt-level.bin'))
PY

for target in "${TARGETS[@]}"; do
    echo "fuzzing $target: $DESCRIBED"
    start=$(date +%s)
    log="$work/$target.log"
    status=0
    (cd fuzz && cargo +nightly fuzz run "$target" "../$corpus/$target" -- \
        "${LIMIT[@]}" -seed=1 -max_len=4194304 -rss_limit_mb=4096 -timeout=30 -print_final_stats=1) >"$log" 2>&1 || status=$?
    grep -E '^(Done|INFO: Seed|stat::number_of_executed_units|stat::peak_rss_mb|==[0-9]+==|SUMMARY|thread .* panicked)' "$log" || true
    echo "$target: $(( $(date +%s) - start )) s"
    if ls fuzz/artifacts/"$target"/crash-* fuzz/artifacts/"$target"/oom-* fuzz/artifacts/"$target"/timeout-* >/dev/null 2>&1; then
        echo "fuzz.sh: $target found an input that fails; see fuzz/artifacts/$target/" >&2
        exit 1
    fi
    # A target that did not build or start fuzzed nothing: that is a failure too.
    if [[ $status -ne 0 ]] || ! grep -q '^Done' "$log"; then
        tail -n 20 "$log" >&2
        echo "fuzz.sh: $target did not run to the end (exit $status); its log is above" >&2
        exit 1
    fi
done
echo "fuzz.sh: ${TARGETS[*]} each ran $DESCRIBED with no crash, hang or memory blow-up"
