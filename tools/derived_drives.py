#!/usr/bin/env python3
"""Drives you do not have, derived from the labelled ones: a check that a map rule generalises.

  tools/derived_drives.py make OUT SEQ...       derived drive folders in OUT
  tools/derived_drives.py frames OUT SEQ...     a one-frame drive in OUT of every labelled scan of SEQ
  tools/derived_drives.py score OUT BIN CONFIG [--single]
                                                map every drive in OUT with BIN/rawlog-octomap and
                                                CONFIG, score it with ../shared/tools/score_map.py;
                                                --single: also without the drive's terrain model
                                                (driveTerrain and fillGaps false), side by side

`make` writes, for each labelled KITTI drive folder SEQ (velodyne/, labels/, poses.txt, calib.txt),
five drives the shared data does not have:
  NNr2    every 2nd ring (a 32-ring sensor's geometry; rings found where the azimuth wraps, as
          `gseg eval --ring-step` finds them)
  NNr4    every 4th ring (16 rings)
  NNf2    every 2nd frame (the vehicle twice as fast)
  NNlowz  the sensor 0.5 m lower (every point's z + 0.5 in the sensor frame, poses unchanged);
          `score` maps it with distToGround: auto (CONFIG's copy, which must hold a fixed height)
  NNhighz the sensor 0.5 m higher (z - 0.5; a van's or truck's roof), mapped as lowz is
`frames` writes, for each labelled scan of a sequence folder SEQ (velodyne/X.bin with
labels/X.label, no poses needed: e.g. ../shared/data/semantickitti-extra/sequences/10), a drive of
that one frame, named sSEQ_X (the identity pose and calibration): the scans of sequences, scenes and
terrain no labelled drive has, mapped from one scan (the model grows from that scan's own ground).
Labels travel with their points; score_map.py's truth comes from the derived points, so each drive
is scored against what its own sensor saw. `score` prints one line per drive: traversable
precision, recall, unsafe beyond one cell [%] (with --single, the single-scan map's first), then the
mean and worst over the drives.
Writes only under OUT; the shared data is read in place.
"""
import array, json, math, os, re, shutil, subprocess, sys

HERE = os.path.dirname(os.path.abspath(__file__))
SCORER = os.path.join(HERE, '..', '..', 'shared', 'tools', 'score_map.py')
MODES = ('r2', 'r4', 'f2', 'lowz', 'highz')


def rings(p, n, min_ring_points=200):
    """Ring index per point: a new ring where the azimuth wraps (KITTI stores the scan ring by ring)."""
    out, ring, begun, before = [0] * n, 0, 0, 0.0
    for i in range(n):
        az = math.atan2(p[4 * i + 1], p[4 * i])
        if i > 0 and az - before < -math.pi and i - begun > min_ring_points:
            ring, begun = ring + 1, i
        before = az
        out[i] = ring
    return out


def begin(final):
    """A drive is written into a temporary folder beside `final` (returned, with velodyne/ and
    labels/), renamed to `final` at the end: a failed run leaves no half drive. An existing `final`
    is refused."""
    if os.path.exists(final):
        sys.exit(f'{final} exists: remove it or give another OUT')
    out = final + '.partial'
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(os.path.join(out, 'velodyne'))
    os.makedirs(os.path.join(out, 'labels'))
    return out


def derive(seq, final, mode):
    """Writes the derived drive (begin())."""
    for need in ('velodyne', 'labels', 'poses.txt', 'calib.txt'):
        if not os.path.exists(os.path.join(seq, need)):
            sys.exit(f'{seq}: no {need} (a labelled KITTI drive folder has velodyne/, labels/, poses.txt, calib.txt)')
    out = begin(final)
    frames = sorted(f[:-4] for f in os.listdir(os.path.join(seq, 'velodyne')) if f.endswith('.bin'))
    poses = [l for l in open(os.path.join(seq, 'poses.txt')).read().splitlines() if l.strip()]
    if len(poses) < len(frames):
        sys.exit(f'{seq}: {len(frames)} frames but {len(poses)} poses')
    keep = frames[::2] if mode == 'f2' else frames
    shutil.copy(os.path.join(seq, 'calib.txt'), os.path.join(out, 'calib.txt'))
    with open(os.path.join(out, 'poses.txt'), 'w') as f:
        f.write('\n'.join(poses[int(k)] for k in keep) + '\n')
    times = os.path.join(seq, 'times.txt')
    if os.path.exists(times):
        t = open(times).read().splitlines()
        with open(os.path.join(out, 'times.txt'), 'w') as f:
            f.write('\n'.join(t[int(k)] for k in keep) + '\n')
    for n, k in enumerate(keep):
        p = array.array('f')
        p.frombytes(open(os.path.join(seq, 'velodyne', k + '.bin'), 'rb').read())
        lab = array.array('I')
        lab.frombytes(open(os.path.join(seq, 'labels', k + '.label'), 'rb').read())
        if len(p) != 4 * len(lab):
            sys.exit(f'{seq}: frame {k}: {len(p) // 4} points but {len(lab)} labels')
        if mode in ('r2', 'r4'):
            step, ring = int(mode[1]), rings(p, len(lab))
            P, L = array.array('f'), array.array('I')
            for i, r in enumerate(ring):
                if r % step == 0:
                    P.extend(p[4 * i:4 * i + 4])
                    L.append(lab[i])
            p, lab = P, L
        elif mode in ('lowz', 'highz'):
            dz = 0.5 if mode == 'lowz' else -0.5
            for i in range(len(lab)):
                p[4 * i + 2] += dz
        open(os.path.join(out, 'velodyne', f'{n:06d}.bin'), 'wb').write(p.tobytes())
        open(os.path.join(out, 'labels', f'{n:06d}.label'), 'wb').write(lab.tobytes())
    os.rename(out, final)


def frames(out, seqs):
    """One-frame drives of every labelled scan of each sequence folder (begin())."""
    for seq in seqs:
        name = os.path.basename(os.path.normpath(seq))
        velodyne, labels = os.path.join(seq, 'velodyne'), os.path.join(seq, 'labels')
        if not os.path.isdir(velodyne) or not os.path.isdir(labels):
            sys.exit(f'{seq}: no velodyne/ and labels/ (a labelled KITTI sequence folder)')
        scans = sorted(f[:-4] for f in os.listdir(velodyne) if f.endswith('.bin') and os.path.exists(os.path.join(labels, f[:-4] + '.label')))
        if not scans:
            sys.exit(f'{seq}: no scan with its labels')
        for k in scans:
            final = os.path.join(out, f's{name}_{k}')
            points, lab = os.path.getsize(os.path.join(velodyne, k + '.bin')), os.path.getsize(os.path.join(labels, k + '.label'))
            if points != 4 * lab:
                sys.exit(f'{seq}: scan {k}: {points // 16} points but {lab // 4} labels')
            part = begin(final)
            shutil.copy(os.path.join(velodyne, k + '.bin'), os.path.join(part, 'velodyne', '000000.bin'))
            shutil.copy(os.path.join(labels, k + '.label'), os.path.join(part, 'labels', '000000.label'))
            identity = '1 0 0 0 0 1 0 0 0 0 1 0'
            open(os.path.join(part, 'poses.txt'), 'w').write(identity + '\n')
            open(os.path.join(part, 'calib.txt'), 'w').write(f'Tr: {identity}\n')
            open(os.path.join(part, 'times.txt'), 'w').write('0.0\n')
            os.rename(part, final)
            print(f's{name}_{k}', flush=True)


def make(out, seqs):
    for seq in seqs:
        name = os.path.basename(os.path.normpath(seq))
        for mode in MODES:
            derive(seq, os.path.join(out, name + mode), mode)
            print(f'{name}{mode}', flush=True)


def score(out, bindir, config, single=False):
    text = open(config).read()
    if not re.search(r'^distToGround:\s*[0-9.]+', text, re.M):
        sys.exit(f'{config}: needs a fixed distToGround (the lowz and highz drives use a copy with auto)')
    configs = {'': text}
    if single:
        if not re.search(r'^\s*driveTerrain:', text, re.M) or not re.search(r'^\s*fillGaps:', text, re.M):
            sys.exit(f'{config}: --single needs the keys driveTerrain and fillGaps in it')
        configs = {'single_': re.sub(r'^(\s*(?:driveTerrain|fillGaps):)\s*\S+', r'\1 false', text, flags=re.M), '': text}
    paths = {}
    for tag, t in configs.items():
        for auto in (False, True):
            path = os.path.join(out, f'config_{tag}{"auto_height" if auto else "fixed_height"}.yaml')
            open(path, 'w').write(re.sub(r'^distToGround:\s*[0-9.]+', 'distToGround: auto', t, count=1, flags=re.M) if auto else t)
            paths[(tag, auto)] = path
    rows = []
    for d in sorted(e for e in os.listdir(out) if os.path.isdir(os.path.join(out, e, 'velodyne'))):
        folder, rawlog = os.path.join(out, d), os.path.join(out, d + '.rawlog')
        os.makedirs(os.path.join(out, 'maps'), exist_ok=True)
        if not os.path.exists(rawlog):
            subprocess.run([os.path.join(bindir, 'kitti2rawlog'), '-q', '-w', '-i', folder, '-o', rawlog], check=True)
        row = [d]
        for tag in configs:
            prefix = os.path.join(out, 'maps', tag + d)
            subprocess.run([os.path.join(bindir, 'rawlog-octomap'), '-q', '-w', '-i', rawlog, '-o', prefix,
                            '-c', paths[(tag, d.endswith(('lowz', 'highz')))]], check=True)
            m = json.loads(subprocess.run([sys.executable, SCORER, folder, prefix + '_costmap.yaml', '--json'],
                                          check=True, capture_output=True, text=True).stdout)['map']
            row.append((m['trav_P'], m['trav_R'], m['unsafe1']))
        rows.append(row)
        print(f'{d:8s} ' + '  |  '.join(f'P {p:6.2f}  R {r:6.2f}  unsafe1 {u:5.2f} %' for p, r, u in row[1:]), flush=True)
    if rows:
        n = len(rows)
        print('mean     ' + '  |  '.join(
            f'P {sum(r[k][0] for r in rows) / n:6.2f}  R {sum(r[k][1] for r in rows) / n:6.2f}  '
            f'worst: P {min(r[k][0] for r in rows):.2f}, R {min(r[k][1] for r in rows):.2f}, unsafe1 {max(r[k][2] for r in rows):.2f} %'
            for k in range(1, len(configs) + 1)))


if __name__ == '__main__':
    a = sys.argv[1:]
    if len(a) >= 3 and a[0] == 'make':
        make(a[1], a[2:])
    elif len(a) >= 3 and a[0] == 'frames':
        frames(a[1], a[2:])
    elif len(a) in (4, 5) and a[0] == 'score' and (len(a) == 4 or a[4] == '--single'):
        score(a[1], a[2], a[3], single=len(a) == 5)
    else:
        sys.exit(__doc__)
