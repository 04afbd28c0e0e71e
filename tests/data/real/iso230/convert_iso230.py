#!/usr/bin/env python3
"""Convert an ecmc ISO 230-2 data file (``*_ISO230.dat``) to a volmap
recordings CSV (docs/recordings-format.md; the format of
tests/data/ecmc-b02/x_recordings.csv, which this script reproduces byte for
byte from the b02 .dat files and X's raw log).

The .dat file is written by ecmcGetISO230DataFromCAFile.bash (ecmc motion test
tools, anderssandstrom): ``TGT_DATA[i]`` is the commanded target position i,
``REF_DATA_FWD[i,j]`` / ``REF_DATA_BWD[i,j]`` the reference-system reading
(already scaled/offset to axis coordinates) taken just before the test-number
PV was set to ``1<j>0<i>`` (forward, approached from below, i.e. moving +) or
``2<j>0<i>`` (backward, approached from above, moving -).

Note: the ecmc report script ecmcISO230_2.py parses REF_DATA_FWD into its
*backward* table and REF_DATA_BWD into its *forward* table, so the published
``*.md`` reports label the two directions the other way round.  This converter
uses the commanded motion direction: FWD -> dir +1, BWD -> dir -1 (as the
existing ecmc-b02 conversion does; verified against the raw camonitor log of
b02 X, where test 1101 is set at X=-20 after the approach from -20.5).

Output rows: run = cycle j; within a run the forward sweep i=1..N (dir +1)
followed by the backward sweep i=N..1 (dir -1), i.e. the order in which the
measurements were taken.  Deviation e = (reference - target) * 1000 um,
3 decimals.  t_s comes from the optional raw camonitor log (time at which the
test-number PV took the value of this measurement, relative to the first
measurement); without a log the column is empty.

Usage:
  convert_iso230.py DAT [--log RAWLOG] [--axis X] [--source TEXT]
                    [--meta key=value ...] [-o OUT]
"""
import argparse
import datetime as _dt
import re
import sys

_IDX2 = re.compile(r'^(REF_DATA_FWD|REF_DATA_BWD)\s*\[\s*(\d+)\s*,\s*(\d+)\s*\]\s*=\s*(\S+)\s*$')
_IDX1 = re.compile(r'^TGT_DATA\s*\[\s*(\d+)\s*\]\s*=\s*(\S+)\s*$')


def parse_dat(path):
    tgt, fwd, bwd, kv = {}, {}, {}, {}
    with open(path, encoding='utf-8') as f:
        for raw in f:
            line = raw.strip()
            if not line or line.startswith('#') or line.startswith('TEST_DATA='):
                continue
            m = _IDX2.match(line)
            if m:
                d = fwd if m.group(1) == 'REF_DATA_FWD' else bwd
                d[int(m.group(2)), int(m.group(3))] = m.group(4).strip()
                continue
            m = _IDX1.match(line)
            if m:
                tgt[int(m.group(1))] = m.group(2).strip()
                continue
            if '=' in line:
                k, v = line.split('=', 1)
                kv[k.strip()] = v.strip()
    npos = int(kv.get('POSITIONS', max(tgt)))
    ncyc = int(kv.get('CYCLES', 5))
    for i in range(1, npos + 1):
        if i not in tgt:
            raise SystemExit(f'{path}: TGT_DATA[{i}] missing')
        for j in range(1, ncyc + 1):
            for name, d in (('REF_DATA_FWD', fwd), ('REF_DATA_BWD', bwd)):
                if (i, j) not in d:
                    raise SystemExit(f'{path}: {name}[{i},{j}] missing')
    if kv.get('UNIT', 'mm') != 'mm':
        raise SystemExit(f'{path}: UNIT={kv["UNIT"]} not supported (need mm)')
    return tgt, fwd, bwd, kv, npos, ncyc


def parse_log_times(path, test_pv):
    """Map test number -> datetime at which test_pv took that value (first)."""
    times = {}
    with open(path, encoding='utf-8', errors='replace') as f:
        for line in f:
            parts = line.split()
            if len(parts) < 4 or parts[0] != test_pv:
                continue
            try:
                val = int(float(parts[3]))
                t = _dt.datetime.strptime(parts[1] + ' ' + parts[2],
                                          '%Y-%m-%d %H:%M:%S.%f')
            except ValueError:
                continue
            times.setdefault(val, t)
    return times


def fmt_target(s):
    """Keep the target as published (e.g. '-20', '0.5'); normalise '-0'."""
    v = float(s)
    if v == 0:
        return '0'
    txt = s.strip()
    if txt.startswith('.'):
        txt = '0' + txt
    elif txt.startswith('-.'):
        txt = '-0' + txt[1:]
    return txt


def fmt_um(x):
    s = f'{x:.3f}'
    return '0.000' if s == '-0.000' else s


def convert(dat, log=None, axis=None, source=None, meta=()):
    tgt, fwd, bwd, kv, npos, ncyc = parse_dat(dat)
    if axis is None:
        m = re.search(r':([XYZABC])-', kv.get('TGT_SET_PV', ''))
        if not m:
            raise SystemExit('cannot infer axis from TGT_SET_PV; give --axis')
        axis = m.group(1)
    axis = axis.upper()
    lin = axis in 'XYZ'
    poscol = f'{axis.lower()}_mm' if lin else f'{axis.lower()}_deg'
    dircol = f'dir_{axis.lower()}'
    devcol = f'e{axis.lower()}_um' if lin else 'e_um'
    if not lin:
        raise SystemExit('rotary axes not supported by this converter')

    times = None
    if log:
        times = parse_log_times(log, kv.get('TEST_PV', 'IOC_TEST:TestNumber'))

    rows = []  # (run, testnumber, target_str, dir, dev_um)
    for j in range(1, ncyc + 1):
        for i in range(1, npos + 1):
            dev = (float(fwd[i, j]) - float(tgt[i])) * 1000.0
            rows.append((j, 1000 + 100 * j + i, tgt[i], '+1', dev))
        for i in range(npos, 0, -1):
            dev = (float(bwd[i, j]) - float(tgt[i])) * 1000.0
            rows.append((j, 2000 + 100 * j + i, tgt[i], '-1', dev))

    t0 = None
    if times is not None:
        missing = [r[1] for r in rows if r[1] not in times]
        if missing:
            raise SystemExit(f'{log}: test numbers missing in log: {missing[:10]}')
        t0 = times[rows[0][1]]

    out = ['# volmap recordings v1']
    if source:
        out.append(f'# source: {source}')
    out.append(f'# axis: {axis}  (single-axis run: other axes not recorded)')
    for m in meta:
        k, v = m.split('=', 1)
        out.append(f'# {k.strip()}: {v.strip()}')
    out.append(f'run,t_s,{poscol},{dircol},{devcol}')
    for run, tn, t, d, dev in rows:
        ts = ''
        if t0 is not None:
            ts = f'{(times[tn] - t0).total_seconds():.3f}'
        out.append(f'{run},{ts},{fmt_target(t)},{d},{fmt_um(dev)}')
    return '\n'.join(out) + '\n'


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('dat')
    ap.add_argument('--log', help='raw camonitor log (for t_s)')
    ap.add_argument('--axis', help='X, Y or Z (default: from TGT_SET_PV)')
    ap.add_argument('--source', help='text of the "# source:" line')
    ap.add_argument('--meta', action='append', default=[],
                    help='extra "# key: value" metadata line (key=value)')
    ap.add_argument('-o', '--out', help='output file (default stdout)')
    a = ap.parse_args(argv)
    text = convert(a.dat, a.log, a.axis, a.source, a.meta)
    if a.out:
        with open(a.out, 'w', encoding='utf-8', newline='\n') as f:
            f.write(text)
    else:
        sys.stdout.write(text)


if __name__ == '__main__':
    main()
