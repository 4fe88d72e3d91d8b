#!/usr/bin/env bash
# scripts/pipeline/parts.mk: 4 parts with make -j2, merged, equal one mesh2svo run; a lost part
# is rebuilt alone; and the Slurm script submits the same commands (sbatch stubbed).
set -euo pipefail
root="$1" bin="$2"
tmp="$(mktemp -d)"; trap 'rm -rf "$tmp"' EXIT
options="-r 300"
run() { make -s -f "$root/scripts/pipeline/parts.mk" MESH="$root/data/uv-torus.obj" OUT="$tmp/out" \
          BIN="$bin" PARTS=4 OPTIONS="$options" LIMIT=256M -j2 "$@"; }
run
"$bin/mesh2svo" "$root/data/uv-torus.obj" -o "$tmp/whole.svo" $options -q > /dev/null
cmp "$tmp/out/uv-torus.svo" "$tmp/whole.svo" || { echo "merged parts differ from the whole build"; exit 1; }
# An interrupted build: only the missing part is rebuilt, then the merge.
before=$(stat -c %Y.%N "$tmp/out/part-1-of-4.svopart")
sleep 1.1
rm "$tmp/out/part-2-of-4.svopart"
plan=$(run -n)
echo "$plan" | grep -q -- "--pages 2/4" || { echo "the missing part is not rebuilt"; exit 1; }
if echo "$plan" | grep -q -- "--pages [013]/4"; then echo "parts that exist are rebuilt"; exit 1; fi
run
[ "$(stat -c %Y.%N "$tmp/out/part-1-of-4.svopart")" = "$before" ] || { echo "part 1 was rewritten"; exit 1; }
cmp "$tmp/out/uv-torus.svo" "$tmp/whole.svo" || { echo "the rebuilt merge differs"; exit 1; }
# The Slurm script: with sbatch stubbed to run each command here, it makes the same file.
mkdir -p "$tmp/stub"
cat > "$tmp/stub/sbatch" <<'STUB'
#!/usr/bin/env bash
# Runs the wrapped command at once, once per array task; prints a job id.
array="" wrap=""
for a in "$@"; do
  case "$a" in --array=*) array="${a#--array=}" ;; --wrap=*) wrap="${a#--wrap=}" ;; esac
done
if [ -n "$array" ]; then
  for k in ${array//,/ }; do SLURM_ARRAY_TASK_ID=$k bash -c "$wrap"; done
else
  bash -c "$wrap"
fi
echo 1
STUB
chmod +x "$tmp/stub/sbatch"
PATH="$tmp/stub:$PATH" BIN="$bin" "$root/scripts/pipeline/slurm-parts.sh" \
  "$root/data/uv-torus.obj" "$tmp/slurm" 3 "$options" 1G > /dev/null
cmp "$tmp/slurm/uv-torus.svo" "$tmp/whole.svo" || { echo "the Slurm route differs"; exit 1; }
echo "parts pipeline ok"
