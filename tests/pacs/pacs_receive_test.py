#!/usr/bin/env python3
"""vpm as a DICOM node (vpm-server --dicom-listen) and C-MOVE, against
Debian's Orthanc on loopback, which knows vpm's listener as the modality
`vpm` (AE title VPM) and as `vpm-wrong` (the same port, a wrong AE title).

(a) Orthanc sends the kidney CT to vpm (REST POST /modalities/vpm/store):
    the "inbox" endpoint searches and lists it, alice loads it with every
    slice at its ImagePositionPatient, bob (not in its users) is refused;
(b) a "retrieve": "move" endpoint loads the kidney CT by C-MOVE into vpm's
    listener, with the same geometry;
(c) faults: a wrong called AE title is rejected, a full store refuses a
    second series and keeps nothing of it, the structured report is refused,
    and the server keeps serving;
(d) the audit log records "receive" (calling AE, UIDs, instances, result)
    and no patient name, ID or birth date is in the server's log or the
    audit log; SIGTERM stops the server (listener included) within its grace.

Usage: pacs_receive_test.py BUILD_DIR SOURCE_DIR
"""
import json
import os
import signal
import subprocess
import sys
import time
import urllib.error

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pacs_harness import Failures, Harness, free_port  # noqa: E402
from pacs_orthanc_test import audit_records, slices_geometry  # noqa: E402

import numpy  # noqa: E402

STUDY = '1.2.826.0.1.3680043.8.498.77040'
CT_SERIES = STUDY + '.1'
CT2_SERIES = STUDY + '.2'
SR_SERIES = STUDY + '.9'
PATIENT_NAME = 'RECEIVE^TESTPATIENT'
PATIENT_ID = 'VPMPAT0088'
BIRTH_DATE = '19700707'
ORTHANC_PASSWORD = 'orthanc-pw-88f2b1'
# The kidney CT is about 2.9 MB as sent; the store takes one copy, not two.
STORE_BYTES = 4_500_000


def main():
    build, source = sys.argv[1], sys.argv[2]
    h = Harness(build)
    t = Failures()
    try:
        run(h, t, build, source)
    finally:
        h.close(keep=t.count > 0)
    print(f'{t.count} failure(s)')
    return 1 if t.count else 0


def orthanc_post(h, path, body):
    """POST a JSON body to Orthanc; (HTTP status, text)."""
    try:
        answer = h.orthanc_request('POST', path, 'vpm', ORTHANC_PASSWORD,
                                   json.dumps(body).encode(), 'application/json')
        return 200, json.dumps(answer)
    except urllib.error.HTTPError as e:
        return e.code, e.read().decode(errors='replace')


def orthanc_series_id(h, series_uid):
    found = h.orthanc_request('POST', '/tools/lookup', 'vpm', ORTHANC_PASSWORD,
                              series_uid.encode(), 'text/plain')
    return next(r['ID'] for r in found if r['Type'] == 'Series')


def send_to_vpm(h, modality, series_uid):
    return orthanc_post(h, f'/modalities/{modality}/store',
                        {'Resources': [orthanc_series_id(h, series_uid)], 'Synchronous': True})


def load_orthanc(h, t, source, listen_port):
    kidney, report = h.write_kidney_study(source, STUDY, PATIENT_NAME, PATIENT_ID, BIRTH_DATE,
                                          '20240612')
    writer = os.path.join(h.build, 'tests', 'pacs', 'vpm_test_write_dicom_series')
    kidney2 = os.path.join(h.tmp, 'kidney2')
    subprocess.run([writer, os.path.join(source, 'tests/data/ct-abdomen-kidney/ct_abdomen.nii.gz'),
                    kidney2, '--series-uid', CT2_SERIES, '--series-number', '3', '--description',
                    'Abdomen copy', '--study-uid', STUDY, '--patient-name', PATIENT_NAME,
                    '--patient-id', PATIENT_ID, '--birth-date', BIRTH_DATE, '--study-date',
                    '20240612'], check=True, capture_output=True)
    h.start_orthanc({'vpm': ORTHANC_PASSWORD}, dimse=True,
                    modalities={'vpm': ['VPM', '127.0.0.1', listen_port],
                                'vpm-wrong': ['NOTVPM', '127.0.0.1', listen_port]})
    n = sum(h.orthanc_upload_folder(f, 'vpm', ORTHANC_PASSWORD) for f in (kidney, report, kidney2))
    t.check(n == 225, f'Orthanc took {n} instances (2 x 112 CT slices and the SR)')
    return kidney


def check_geometry(t, vol, g, what):
    direction = numpy.array(vol['direction_columns_lps'])
    origin = numpy.array(vol['origin_lps_mm'])
    spacing = vol['spacing_mm']
    worst = max(float(numpy.linalg.norm(origin + direction[2] * spacing[2] * k - p))
                for k, p in enumerate(g['positions']))
    t.check(vol['dims'] == [g['columns'], g['rows'], len(g['positions'])] and worst < 1e-3 and
            vol['min_value'] == g['min'] and vol['max_value'] == g['max'],
            f'{what}: dims, every slice at its ImagePositionPatient (worst {worst:.2e} mm), '
            f'values {vol["min_value"]}..{vol["max_value"]}')


def run(h, t, build, source):
    listen_port = free_port()
    h.listen_port = listen_port
    kidney = load_orthanc(h, t, source, listen_port)
    g = slices_geometry(kidney)
    users = h.write_users(['alice', 'bob'])
    endpoints = h.write_endpoints([
        {'name': 'inbox', 'receive': True, 'users': ['alice']},
        {'name': 'pacs-move', 'dimse': f'ORTHANC@127.0.0.1:{h.orthanc_dicom_port}',
         'calling_aet': 'VPM', 'retrieve': 'move', 'move_destination': 'VPM',
         'users': ['alice']}])
    audit = os.path.join(h.tmp, 'audit.jsonl')
    cache = os.path.join(h.tmp, 'cache')
    h.start_server(users, ['--pacs', endpoints, '--pacs-cache', cache, '--pacs-audit-log', audit,
                           '--dicom-listen', f'VPM@127.0.0.1:{listen_port}',
                           '--dicom-store-bytes', str(STORE_BYTES)])
    received_root = os.path.join(cache, '.received')

    code, text = orthanc_post(h, '/modalities/vpm/echo', {})
    t.check(code == 200, f'Orthanc C-ECHOes vpm ({code} {text[:120]})')

    start = time.monotonic()
    code, text = send_to_vpm(h, 'vpm', CT_SERIES)
    receive_s = time.monotonic() - start
    t.check(code == 200, f'Orthanc sends the kidney CT to vpm ({code} {text[:160]})')
    print(f'      figures: 112 instances received by C-STORE in {receive_s:.2f} s')
    check_inbox(h, t, g)

    start = time.monotonic()
    rc, out, err = h.vpm('alice', 'volume', 'load', f'pacs:pacs-move/{STUDY}/{CT_SERIES}')
    move_s = time.monotonic() - start
    t.check(rc == 0, f'vpm volume load by C-MOVE ({err.strip()[-300:]})')
    if rc == 0:
        check_geometry(t, json.loads(out), g, 'the series moved by C-MOVE')
        print(f'      figures: open by C-MOVE {move_s:.2f} s (112 instances, read, GPU upload)')

    check_faults(h, t, received_root)
    check_logs(h, t, audit)
    check_stop(h, t)


def check_inbox(h, t, g):
    found, err = h.vpm_json('alice', 'pacs', 'search', '--endpoint', 'inbox',
                            '--patient-name', 'receive^test*', '--json')
    studies = (found or {}).get('studies', [])
    t.check(len(studies) == 1 and studies[0]['study_uid'] == STUDY and
            studies[0]['patient_id'] == PATIENT_ID and studies[0]['series_count'] == 1 and
            studies[0]['modalities'] == ['CT'],
            f'the inbox finds the received study by a patient-name wildcard ({err.strip()[-200:]})')
    listed, err = h.vpm_json('alice', 'pacs', 'series', '--endpoint', 'inbox', '--study', STUDY,
                             '--json')
    series = (listed or {}).get('series', [])
    t.check(len(series) == 1 and series[0]['series_uid'] == CT_SERIES and
            series[0]['instance_count'] == 112 and
            series[0]['source'] == f'pacs:inbox/{STUDY}/{CT_SERIES}',
            f'the inbox lists the CT with its 112 instances ({err.strip()[-200:]})')
    source = f'pacs:inbox/{STUDY}/{CT_SERIES}'
    start = time.monotonic()
    rc, out, err = h.vpm('alice', 'volume', 'load', source)
    t.check(rc == 0, f'alice loads {source} ({err.strip()[-300:]})')
    if rc == 0:
        check_geometry(t, json.loads(out), g, 'the received series')
        print(f'      figures: open of the received series {time.monotonic() - start:.2f} s')
    for args in (['pacs', 'search', '--endpoint', 'inbox'], ['volume', 'load', source]):
        rc, _, err = h.vpm('bob', *args)
        t.check(rc != 0 and 'PERMISSION_DENIED' in err, f'bob: {" ".join(args[:2])} refused')


def check_faults(h, t, received_root):
    code, text = send_to_vpm(h, 'vpm-wrong', CT_SERIES)
    t.check(code != 200, f'a wrong called AE title is rejected ({code} {text[:120]})')
    echo = subprocess.run(['echoscu', '-aec', 'NOTVPM', '127.0.0.1', str(h.listen_port)],
                          capture_output=True, text=True, timeout=30)
    t.check('Rejected' in (echo.stdout + echo.stderr),
            'echoscu with a wrong called AE title: association rejected')
    code, text = send_to_vpm(h, 'vpm', CT2_SERIES)
    listed, _ = h.vpm_json('alice', 'pacs', 'series', '--endpoint', 'inbox', '--study', STUDY,
                           '--json')
    uids = [s['series_uid'] for s in (listed or {}).get('series', [])]
    leftovers = [n for n in os.listdir(received_root) if n.startswith('.tmp-')]
    t.check(code != 200 and uids == [CT_SERIES] and
            not os.path.exists(os.path.join(received_root, 'series', CT2_SERIES)) and not leftovers,
            f'the full store refuses a second series and keeps nothing of it ({code})')
    code, text = send_to_vpm(h, 'vpm', SR_SERIES)
    listed, _ = h.vpm_json('alice', 'pacs', 'series', '--endpoint', 'inbox', '--study', STUDY,
                           '--json')
    uids = [s['series_uid'] for s in (listed or {}).get('series', [])]
    t.check(code != 200 and uids == [CT_SERIES], f'the structured report is refused ({code})')
    t.check(h.server_alive(), 'the server keeps serving')


def check_logs(h, t, audit):
    records = [r for r in audit_records(audit) if r['action'] == 'receive']
    by_series = {r['series_uid']: r for r in records}
    ct = by_series.get(CT_SERIES, {})
    t.check(ct.get('result') == 'OK' and ct.get('calling_aet') == 'ORTHANC' and
            ct.get('instances') == 112 and ct.get('study_uid') == STUDY and 'time' in ct,
            f'the audit log has the receive of the CT: {json.dumps(ct)[:300]}')
    t.check(by_series.get(CT2_SERIES, {}).get('result') == 'RESOURCE_EXHAUSTED',
            'the audit log has the refused second series (RESOURCE_EXHAUSTED)')
    t.check(by_series.get(SR_SERIES, {}).get('result') == 'FAILED_PRECONDITION',
            'the audit log has the refused report (FAILED_PRECONDITION)')
    opens = {(r['user'], r['endpoint'], r['result']) for r in audit_records(audit)
             if r['action'] == 'open'}
    t.check({('alice', 'inbox', 'OK'), ('alice', 'pacs-move', 'OK'),
             ('bob', 'inbox', 'PERMISSION_DENIED')} <= opens, 'the audit log has the opens')
    with open(h.server_log) as f:
        log = f.read()
    with open(audit) as f:
        audit_text = f.read()
    secrets = [PATIENT_NAME, 'RECEIVE^', PATIENT_ID, BIRTH_DATE, ORTHANC_PASSWORD]
    t.check(not any(s in log for s in secrets) and not any(s in audit_text for s in secrets),
            'neither the server log nor the audit log holds a patient name, ID or birth date')


def check_stop(h, t):
    start = time.monotonic()
    h.server.send_signal(signal.SIGTERM)
    try:
        h.server.wait(timeout=20)
    except subprocess.TimeoutExpired:
        pass
    stop_s = time.monotonic() - start
    t.check(h.server.poll() is not None and stop_s < 4.5,
            f'SIGTERM stops the server and its DICOM node in {stop_s:.2f} s (grace 2 s)')


if __name__ == '__main__':
    sys.exit(main())
