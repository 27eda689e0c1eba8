#!/usr/bin/env python3
"""vpm against a misbehaving DICOMweb server (fake_dicomweb.py), through
vpm-server --pacs and the `vpm` client: the quirks real servers have
(unquoted boundary, parts without Content-Length, a preamble, `offset`
ignored) must work; the faults (a truncated multipart body, HTTP 401, 403,
404 and 500 on the listing and on the retrieval, a structured report, mixed
series, a part that is not DICOM, a server that stalls past the call's
deadline) must each give a clear error, leave nothing in the cache and the
server serving.

Usage: pacs_faults_test.py BUILD_DIR SOURCE_DIR
"""
import json
import os
import re
import shutil
import subprocess
import sys
import time
import urllib.request

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pacs_harness import Failures, Harness  # noqa: E402

STUDY = '1.2.826.0.1.3680043.8.498.88020'
CT_SERIES = STUDY + '.1'
SR_SERIES = STUDY + '.9'


def main():
    build, source = sys.argv[1], sys.argv[2]
    h = Harness(build)
    t = Failures()
    try:
        run(h, t, build, source)
    finally:
        h.close()
    print(f'{t.count} failure(s)')
    return 1 if t.count else 0


def run(h, t, build, source):
    base = start_fake_dicomweb(h, build, source)
    cache, audit = start_server(h, base)
    paging_checks(h, t, base)
    load_checks(h, t, cache)
    table = fault_checks(h, t, cache)
    stall_checks(h, t, cache, audit)
    print('      fault table:')
    for mode, err in table:
        print(f'        {mode:10s} {err[-200:]}')


def start_fake_dicomweb(h, build, source):
    """The kidney CT, an SR and another series written to folders, served by
    fake_dicomweb.py; returns its base URL."""
    writer = os.path.join(build, 'tests', 'pacs', 'vpm_test_write_dicom_series')
    common = ['--study-uid', STUDY, '--patient-name', 'FAKE^PATIENT', '--patient-id', 'FAKE0',
              '--birth-date', '19800101', '--study-date', '20240101']
    ct, sr, other = (os.path.join(h.tmp, n) for n in ('ct', 'sr', 'other'))
    subprocess.run([writer, os.path.join(source, 'tests/data/ct-abdomen-kidney/ct_abdomen.nii.gz'),
                    ct, '--series-uid', CT_SERIES] + common, check=True, capture_output=True)
    subprocess.run([writer, '--structured-report', sr, '--series-uid', SR_SERIES] + common,
                   check=True, capture_output=True)
    os.makedirs(other)
    shutil.copy(os.path.join(source, 'tests/data/ct-philips-tilt/I10'), other)
    port_file = os.path.join(h.tmp, 'fake.port')
    fake = subprocess.Popen([sys.executable, os.path.join(os.path.dirname(__file__), 'fake_dicomweb.py'),
                             ct, sr, other, port_file])
    h.procs.append(fake)
    for _ in range(200):
        if os.path.exists(port_file):
            break
        time.sleep(0.05)
    port = int(open(port_file).read())
    return f'http://127.0.0.1:{port}'


def start_server(h, base):
    """vpm-server with one endpoint per fault mode of the fake server (and a
    good and a wrong bearer token); returns the cache's and the audit log's
    paths."""
    h.write_secret('good.token', 'good-token')
    h.write_secret('wrong.token', 'wrong-token')
    modes = ['quirky', 'truncated', 's401', 's403', 's404', 's500', 'w401', 'w403', 'w404', 'w500',
             'sr', 'mixed', 'notdicom', 'stall', 'slow']
    endpoints = [{'name': 'good', 'dicomweb': f'{base}/good', 'bearer_token_file': 'good.token',
                  'users': ['alice'], 'page_size': 2},
                 {'name': 'badtoken', 'dicomweb': f'{base}/good', 'bearer_token_file': 'wrong.token',
                  'users': ['alice']}]
    endpoints += [{'name': m, 'dicomweb': f'{base}/{m}', 'users': ['*'], 'page_size': 2} for m in modes]
    users = h.write_users(['alice'])
    cache = os.path.join(h.tmp, 'cache')
    audit = os.path.join(h.tmp, 'audit.jsonl')
    h.start_server(users, ['--pacs', h.write_endpoints(endpoints), '--pacs-cache', cache,
                           '--pacs-audit-log', audit])
    return cache, audit


def load(h, mode, *extra):
    return h.vpm('alice', *extra, 'volume', 'load', f'pacs:{mode}/{STUDY}/{CT_SERIES}')


def cached(cache, mode):
    return os.path.exists(os.path.join(cache, mode)) and os.listdir(os.path.join(cache, mode))


def paging_checks(h, t, base):
    """Paging with offset, a server that ignores it, --limit."""
    def counts():
        with urllib.request.urlopen(f'{base}/_counts', timeout=10) as r:
            return json.loads(r.read())

    # Paging: a server that honours offset, 5 studies in pages of 2.
    found, err = h.vpm_json('alice', 'pacs', 'search', '--endpoint', 'good', '--json')
    t.check(found is not None and len(found['studies']) == 5 and not found['truncated']
            and counts().get('good') == 3, f'paging with offset: 5 studies in 3 pages ({err.strip()})')
    # A server that ignores offset: the search ends instead of looping.
    found, err = h.vpm_json('alice', 'pacs', 'search', '--endpoint', 'quirky', '--json')
    t.check(found is not None and len(found['studies']) == 2 and found['truncated']
            and counts().get('quirky') == 2,
            f'offset ignored: 2 distinct studies, marked truncated, after 2 requests ({err.strip()})')
    found, _ = h.vpm_json('alice', 'pacs', 'search', '--endpoint', 'good', '--limit', '3', '--json')
    t.check(found is not None and len(found['studies']) == 3 and found['truncated'], '--limit 3 of 5')


def load_checks(h, t, cache):
    """Loads that work: a bearer token (and a wrong one refused), a quirky
    multipart answer, a slow retrieval with its progress."""
    rc, out, err = load(h, 'good')
    t.check(rc == 0 and json.loads(out)['dims'] == [122, 101, 112],
            f'a bearer-token endpoint: the series loads ({err.strip()[-200:]})')
    rc, _, err = h.vpm('alice', 'pacs', 'search', '--endpoint', 'badtoken')
    t.check(rc != 0 and 'PERMISSION_DENIED' in err and 'wrong-token' not in err,
            f'a wrong bearer token: {err.strip()}')
    rc, out, err = load(h, 'quirky')
    vol = json.loads(out) if rc == 0 else {}
    t.check(rc == 0 and vol.get('dims') == [122, 101, 112] and vol.get('min_value') == -1207,
            f'unquoted boundary, parts without Content-Length, a preamble: loads ({err.strip()[-200:]})')
    t.check(bool(cached(cache, 'quirky')), 'and is cached')
    rc, _, err = h.vpm('alice', 'volume', 'load', '--progress', f'pacs:slow/{STUDY}/{CT_SERIES}')
    stages = [s for s in ('retrieving', 'reading', 'uploading') if s in err]
    percents = [int(p) for p in re.findall(r'\] +(\d+)%', err)]
    t.check(rc == 0 and 'retrieving' in stages and len(set(percents)) >= 3 and
            percents == sorted(percents),
            f'a 3 s retrieval reports progress: stages {stages}, {len(set(percents))} distinct '
            f'fractions, never decreasing')


def fault_checks(h, t, cache):
    """Each fault mode answers its status code and words, nothing cached;
    returns (mode, error) for the table."""
    expect = {
        'truncated': ('INVALID_ARGUMENT', 'truncated'),
        's401': ('PERMISSION_DENIED', 'HTTP 401'),
        's403': ('PERMISSION_DENIED', 'HTTP 403'),
        's404': ('NOT_FOUND', 'HTTP 404'),
        's500': ('UNAVAILABLE', 'HTTP 500'),
        'w401': ('PERMISSION_DENIED', 'retrieve series'),
        'w403': ('PERMISSION_DENIED', 'HTTP 403'),
        'w404': ('NOT_FOUND', 'HTTP 404'),
        'w500': ('UNAVAILABLE', 'HTTP 500'),
        'sr': ('INVALID_ARGUMENT', 'holds no images'),
        'mixed': ('INVALID_ARGUMENT', 'instances of series'),
        'notdicom': ('INVALID_ARGUMENT', 'not a DICOM file'),
    }
    table = []
    for mode, (code, words) in expect.items():
        rc, _, err = load(h, mode)
        table.append((mode, err.strip()))
        t.check(rc != 0 and code in err and words in err and not cached(cache, mode),
                f'{mode}: {code}, "{words}", nothing cached: {err.strip()[-220:]}')
    for status, code in (('s401', 'PERMISSION_DENIED'), ('s500', 'UNAVAILABLE')):
        rc, _, err = h.vpm('alice', 'pacs', 'series', '--endpoint', status, '--study', STUDY)
        t.check(rc != 0 and code in err, f'series listing on {status}: {code}')
    return table


def stall_checks(h, t, cache, audit):
    """A stalled transfer ends at the call's deadline, leaves nothing behind
    and is audited; the server keeps serving."""
    start = time.monotonic()
    rc, _, err = load(h, 'stall', '--deadline-s', '3')
    took = time.monotonic() - start
    t.check(rc != 0 and 'DEADLINE_EXCEEDED' in err and took < 20 and not cached(cache, 'stall'),
            f'a stalled transfer ends at the call\'s deadline ({took:.1f} s): {err.strip()[-160:]}')
    time.sleep(1.5)  # the server's side of the cancelled load
    t.check(not [n for n in os.listdir(cache) if n.startswith('.tmp-')], 'no temporary folder is left behind')
    stalled = [r for r in map(json.loads, open(audit)) if r['endpoint'] == 'stall']
    t.check(bool(stalled) and stalled[-1]['result'] in ('DEADLINE_EXCEEDED', 'CANCELLED'),
            'the cancelled open is audited as such')
    rc, _, _ = h.vpm('alice', 'volume', 'list')
    t.check(rc == 0 and h.server_alive(), 'the server keeps serving')


if __name__ == '__main__':
    sys.exit(main())
