#!/bin/sh
# Usage: check_layers.sh CXX VIEWS_DIR SOURCE_DIR. Each layer's include view must let a file of
# that layer include the layers below it (right_way.cpp compiles) and not the layers above it
# (wrong_way.cpp fails with "No such file").
set -u
cxx=$1 views=$2 here=$3
flags="-std=c++20 -fsyntax-only -I$views/integrators -isystem /usr/include/stb"
if ! $cxx $flags "$here/right_way.cpp" 2>/tmp/caustica_layers_right.txt; then
  echo "FAIL: a right-way include did not compile:"; cat /tmp/caustica_layers_right.txt; exit 1
fi
if $cxx $flags "$here/wrong_way.cpp" 2>/tmp/caustica_layers_wrong.txt; then
  echo "FAIL: integrators/ could include render/renderer.h"; exit 1
fi
grep -q "render/renderer.h" /tmp/caustica_layers_wrong.txt || { cat /tmp/caustica_layers_wrong.txt; exit 1; }
echo "ok: integrators sees film/ but not render/"
