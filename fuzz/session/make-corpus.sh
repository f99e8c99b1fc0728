#!/bin/sh
# Writes the session fuzzer's seed corpus: small sessions saved by `tendril edit --save` from
# the documents fuzzer's small scenes (climbing, particle, L-system and wind plants, simulated
# air; one with edits and their journal). Usage: fuzz/session/make-corpus.sh TENDRIL OUTPUT_DIR
set -eu
tendril=$1
out=$2
corpus=$(cd "$(dirname "$0")/../documents/corpus" && pwd)
mkdir -p "$out"
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
printf '{"tendril_edits": 1, "edits": []}\n' > "$work/none.json"
save() {  # save NAME SCENE SCRIPT STEPS
  "$tendril" edit "$corpus/$2" --script "$3" --steps "$4" -o "$work/out" --format obj -q --threads 1 \
    --save "$out/$1.tses"
}
save edited climb.json "$corpus/edits.json" 10
save climb climb.json "$work/none.json" 8
save particles particles.json "$work/none.json" 8
save lsystem lsystem.json "$work/none.json" 3
save gusty gusty.json "$work/none.json" 4
save air air.json "$work/none.json" 4
save air-position-based air-position-based.json "$work/none.json" 4
