#!/bin/sh
# build_java_types.sh OUT_JAR WORK_DIR LCM_FILE... : lcm-gen -j, javac against lcm.jar, jar.
set -e
out=$1; work=$2; shift 2
rm -rf "$work"; mkdir -p "$work/src" "$work/classes"
lcm-gen --java --jpath "$work/src" "$@"
find "$work/src" -name '*.java' > "$work/sources.txt"
javac -nowarn -cp /usr/share/java/lcm.jar -d "$work/classes" @"$work/sources.txt"
jar cf "$out" -C "$work/classes" .
