#!/usr/bin/env python3
"""Time from Open to the first frame of a series from a PACS through
vpm-server, as the viewers open it (LoadVolume, OpenSession with the
default proxy mesh, one still frame): first (retrieved from Orthanc by
WADO-RS, read, uploaded to the GPU) and cached (another user's open of the
same series, read from the disk cache).

Writes a synthetic int16 CT of X x Y x Z voxels as a DICOM series
(vpm_test_write_dicom_series), loads it into Debian's Orthanc (started as in
tests/pacs, loopback, authentication on) and times `vpm volume load
pacs:...` for two users, N rounds (a new server each round, so that the
first open always retrieves).

Usage: pacs_open_bench.py BUILD_DIR [--dims 512 512 300] [--rounds 3]
"""
import argparse
import json
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'tests', 'pacs'))
from pacs_harness import Harness  # noqa: E402

import numpy  # noqa: E402

STUDY = '1.2.826.0.1.3680043.8.498.99030'


def open_to_first_frame(h, user, source):
    """Seconds of LoadVolume, OpenSession and the first still frame."""
    times = []
    start = time.monotonic()
    rc, out, err = h.vpm(user, 'volume', 'load', source)
    times.append(time.monotonic() - start)
    if rc != 0:
        raise SystemExit(err)
    volume_id = json.loads(out)['volume_id']
    start = time.monotonic()
    session, err = h.vpm_json(user, 'session', 'open', '--volume-id', volume_id)
    times.append(time.monotonic() - start)
    if session is None:
        raise SystemExit(err)
    start = time.monotonic()
    rc, _, err = h.vpm(user, 'snapshot', '--session', session['session_id'], '--size', '512', '512',
                       '--out', os.path.join(h.tmp, f'{user}.jpg'))
    times.append(time.monotonic() - start)
    if rc != 0:
        raise SystemExit(err)
    return times


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument('build')
    parser.add_argument('--dims', type=int, nargs=3, default=[512, 512, 300])
    parser.add_argument('--rounds', type=int, default=3)
    args = parser.parse_args()
    h = Harness(args.build)
    try:
        nx, ny, nz = args.dims
        raw = os.path.join(h.tmp, 'ct.raw')
        z, y, x = numpy.mgrid[0:nz, 0:ny, 0:nx]
        values = (1000 * numpy.sin(x / 37.0) * numpy.cos(y / 23.0) + 3 * z - 200).astype(numpy.int16)
        values.tofile(raw)
        del z, y, x, values
        series = STUDY + '.1'
        folder = os.path.join(h.tmp, 'series')
        subprocess.run([os.path.join(args.build, 'tests', 'pacs', 'vpm_test_write_dicom_series'),
                        f'raw:{raw}?dims={nx},{ny},{nz}&type=int16&spacing=0.7,0.7,1.0', folder,
                        '--study-uid', STUDY, '--series-uid', series, '--patient-name', 'BENCH^SERIES',
                        '--patient-id', 'BENCH1'], check=True, capture_output=True)
        base = h.start_orthanc({'vpm': 'bench-pw'})
        start = time.monotonic()
        n = h.orthanc_upload_folder(folder, 'vpm', 'bench-pw')
        print(f'Orthanc took {n} instances in {time.monotonic() - start:.1f} s')
        h.write_secret('orthanc.pw', 'bench-pw')
        endpoints = h.write_endpoints([{'name': 'orthanc', 'dicomweb': base, 'username': 'vpm',
                                        'password_file': 'orthanc.pw', 'users': ['*']}])
        users = h.write_users(['alice', 'bob'])
        source = f'pacs:orthanc/{STUDY}/{series}'
        print(f'{nx} x {ny} x {nz} int16, {n} instances; seconds from Open to the first frame '
              f'of {source}: load + session (proxy mesh) + still frame')
        print('round  first (alice: retrieve)       cached (bob: disk cache)')
        for r in range(args.rounds):
            cache = os.path.join(h.tmp, f'cache{r}')
            h.start_server(users, ['--pacs', endpoints, '--pacs-cache', cache,
                                   '--pacs-audit-log', os.path.join(h.tmp, 'audit.jsonl')])
            times = [open_to_first_frame(h, user, source) for user in ('alice', 'bob')]
            print(f'{r + 1:5d}  ' + '  '.join(
                f'{sum(t):5.2f} ({t[0]:.2f} + {t[1]:.2f} + {t[2]:.2f})' for t in times))
            h.server.terminate()
            h.server.wait()
    finally:
        h.close()


if __name__ == '__main__':
    main()
