#!/usr/bin/env python3
"""Runs ../shared/tools/score_map.py (unchanged, imported) on several maps of one drive, reading the
drive's points once: usage: score_map_batch.py SCORE_MAP_PY DRIVE_SEQ_DIR [--clearance C] [--elevation T] MAP.yaml [[...] MAP.yaml]...
(an option applies to the maps after it). Prints one JSON line per map (score_map.py --json's), in order. For the tests of gseg eval-map."""
import importlib.util, sys

spec = importlib.util.spec_from_file_location('score_map', sys.argv[1])
sm = importlib.util.module_from_spec(spec)
spec.loader.exec_module(sm)
seq, rest = sys.argv[2], sys.argv[3:]
points = list(sm.drive_points(seq))
sm.drive_points = lambda s: iter(points)
options = {}
while rest:
    if rest[0] in ('--clearance', '--elevation'):
        options[rest[0]], rest = rest[1], rest[2:]
        continue
    sys.argv = ['score_map.py', seq, rest[0], '--json'] + [a for kv in options.items() for a in kv]
    rest = rest[1:]
    sm.main()
    sys.stdout.flush()
