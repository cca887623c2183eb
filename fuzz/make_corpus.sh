#!/bin/sh
# Seeds the fuzzing corpus with the shared scenes (scenes/ in the repository) and the regression
# inputs in tests/data/pbrt_crashers. Usage: fuzz/make_corpus.sh [corpus-dir]
set -e
here=$(cd "$(dirname "$0")" && pwd)
corpus=${1:-$here/../build-fuzz/corpus}
mkdir -p "$corpus"
for f in "$here"/../scenes/*.pbrt "$here"/../scenes/pbrt-v4/*/scene-v4.pbrt; do
  name=$(echo "$f" | sed 's|.*/scenes/||; s|/|_|g')
  cp "$f" "$corpus/seed_$name"
done
for f in "$here"/../tests/data/pbrt_crashers/*; do
  case "$f" in *README.md) ;; *) cp "$f" "$corpus/";; esac
done
echo "corpus: $corpus ($(ls "$corpus" | wc -l) files)"
