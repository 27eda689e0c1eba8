#!/usr/bin/env python3
"""vpm against a PACS by DICOM networking (DIMSE): Debian's Orthanc with its
DICOM server on loopback, knowing vpm as the modality VPM. Loaded (by its
REST API) with the kidney CT written as a DICOM series and a structured
report in the same study. Through vpm-server --pacs with a "dimse" endpoint
and the `vpm` client: C-FIND study search (wildcard, patient ID, date range,
modality), C-FIND series listing, `vpm volume load pacs:...` retrieved by
C-GET with its geometry checked against the slices' own positions, the SR
refused with nothing cached, a grab and drag exported back by C-STORE and
found in the study, a wrong called AE title (PERMISSION_DENIED), a node
that is not there (UNAVAILABLE), the audit log, and no patient identifier
in the server's log.

Usage: pacs_dimse_test.py BUILD_DIR SOURCE_DIR
"""
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pacs_harness import Failures, Harness, free_port  # noqa: E402
from pacs_orthanc_test import audit_records, slices_geometry, thumbnail_checks  # noqa: E402

import numpy  # noqa: E402

STUDY = '1.2.826.0.1.3680043.8.498.77030'
CT_SERIES = STUDY + '.1'
SR_SERIES = STUDY + '.9'
# Beyond ASCII: Orthanc answers C-FIND in its own character set (Latin-1 by
# default), which vpm converts to UTF-8.
PATIENT_NAME = 'DIMSE^TESTPATIENTÖ'
PATIENT_ID = 'VPMPAT0077'
BIRTH_DATE = '19650505'
ORTHANC_PASSWORD = 'orthanc-pw-77e1a0'


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


def load_orthanc(h, t, build, source):
    kidney, report = h.write_kidney_study(source, STUDY, PATIENT_NAME, PATIENT_ID, BIRTH_DATE,
                                          '20240611')
    h.start_orthanc({'vpm': ORTHANC_PASSWORD}, dimse=True)
    n = h.orthanc_upload_folder(kidney, 'vpm', ORTHANC_PASSWORD)
    n += h.orthanc_upload_folder(report, 'vpm', ORTHANC_PASSWORD)
    t.check(n == 113, f'Orthanc took {n} instances (112 CT slices and the SR)')
    return kidney


def run(h, t, build, source):
    kidney = load_orthanc(h, t, build, source)
    port = h.orthanc_dicom_port
    users = h.write_users(['alice', 'bob'])
    endpoints = h.write_endpoints([
        {'name': 'pacs', 'dimse': f'ORTHANC@127.0.0.1:{port}', 'calling_aet': 'VPM',
         'users': ['alice']},
        {'name': 'wrong-aet', 'dimse': f'NOTORTHANC@127.0.0.1:{port}', 'users': ['alice']},
        {'name': 'nowhere', 'dimse': f'ORTHANC@127.0.0.1:{free_port()}', 'users': ['alice']}])
    audit = os.path.join(h.tmp, 'audit.jsonl')
    cache = os.path.join(h.tmp, 'cache')
    h.start_server(users, ['--pacs', endpoints, '--pacs-cache', cache, '--pacs-audit-log', audit])
    find_checks(h, t)
    thumbnail_checks(h, t, 'pacs', STUDY, CT_SERIES, SR_SERIES, 'C-FIND and C-GET of one instance')
    vol = get_checks(h, t, kidney, cache)
    export_back(h, t, vol)
    failure_checks(h, t)
    privacy_checks(h, t, audit)


def find_checks(h, t):
    """C-FIND: studies by name wildcard, ID, date range and modality; the
    study's series."""
    found, err = h.vpm_json('alice', 'pacs', 'search', '--endpoint', 'pacs',
                            '--patient-name', 'DIMSE^TEST*', '--json')
    studies = (found or {}).get('studies', [])
    t.check(len(studies) == 1 and studies[0]['study_uid'] == STUDY and
            studies[0]['patient_id'] == PATIENT_ID and studies[0]['patient_birth_date'] == BIRTH_DATE
            and studies[0]['patient_name'] == PATIENT_NAME
            and set(studies[0]['modalities']) >= {'CT', 'SR'} and studies[0]['series_count'] == 2,
            f'C-FIND by patient-name wildcard finds the study, CT and SR, 2 series, the name in UTF-8 '
            f'({(studies or [{}])[0].get("patient_name")!r}; {err.strip()})')
    found, err = h.vpm_json('alice', 'pacs', 'search', '--endpoint', 'pacs',
                            '--patient-name', 'DIMSE^TESTPATIENTÖ*', '--json')
    t.check([s['study_uid'] for s in (found or {}).get('studies', [])] == [STUDY],
            f'C-FIND by a name beyond ASCII (the keys declared UTF-8) ({err.strip()})')
    found, _ = h.vpm_json('alice', 'pacs', 'search', '--endpoint', 'pacs', '--patient-id', PATIENT_ID,
                          '--study-date', '20240101-20241231', '--modality', 'CT', '--json')
    t.check([s['study_uid'] for s in (found or {}).get('studies', [])] == [STUDY],
            'C-FIND by patient ID, study-date range and modality')
    found, _ = h.vpm_json('alice', 'pacs', 'search', '--endpoint', 'pacs', '--study-date',
                          '20250101-', '--json')
    t.check(found is not None and found['studies'] == [], 'a date range after the study finds nothing')

    listed, err = h.vpm_json('alice', 'pacs', 'series', '--endpoint', 'pacs', '--study', STUDY, '--json')
    series = {s['series_uid']: s for s in (listed or {}).get('series', [])}
    ct = series.get(CT_SERIES, {})
    t.check(len(series) == 2 and ct.get('modality') == 'CT' and ct.get('instance_count') == 112 and
            ct.get('source') == f'pacs:pacs/{STUDY}/{CT_SERIES}',
            f'C-FIND series listing: CT of 112 images and the SR ({err.strip()})')


def get_checks(h, t, kidney, cache):
    """The kidney CT opened by C-GET, its geometry and values against the
    slices'; the SR refused. Returns the volume."""
    source_ct = f'pacs:pacs/{STUDY}/{CT_SERIES}'
    start = time.monotonic()
    rc, out, err = h.vpm('alice', 'volume', 'load', source_ct)
    load_s = time.monotonic() - start
    vol = json.loads(out) if rc == 0 else {}
    t.check(rc == 0, f'vpm volume load {source_ct} by C-GET ({err.strip()[-300:]})')
    if vol:
        g = slices_geometry(kidney)
        direction = numpy.array(vol['direction_columns_lps'])
        origin = numpy.array(vol['origin_lps_mm'])
        spacing = vol['spacing_mm']
        worst = max(float(numpy.linalg.norm(origin + direction[2] * spacing[2] * k - p))
                    for k, p in enumerate(g['positions']))
        t.check(vol['dims'] == [g['columns'], g['rows'], len(g['positions'])] and worst < 1e-3 and
                vol['min_value'] == g['min'] and vol['max_value'] == g['max'],
                f'the retrieved series: dims, every slice at its ImagePositionPatient '
                f'(worst {worst:.2e} mm), values {vol["min_value"]}..{vol["max_value"]}')
        print(f'      figures: open by C-GET {load_s:.2f} s (112 instances, read, GPU upload)')
    rc, _, err = h.vpm('alice', 'volume', 'load', f'pacs:pacs/{STUDY}/{SR_SERIES}')
    t.check(rc != 0 and 'INVALID_ARGUMENT' in err and 'holds no images' in err and
            not os.path.exists(os.path.join(cache, 'pacs', SR_SERIES)),
            f'the SR is refused, nothing cached: {err.strip()[-160:]}')
    return vol


def failure_checks(h, t):
    """A wrong called AE title, a node that is not there, a forbidden user."""
    rc, _, err = h.vpm('alice', 'pacs', 'search', '--endpoint', 'wrong-aet')
    t.check(rc != 0 and 'PERMISSION_DENIED' in err and 'AE title' in err,
            f'a called AE title the PACS is not: {err.strip()[-200:]}')
    rc, _, err = h.vpm('alice', 'pacs', 'search', '--endpoint', 'nowhere')
    t.check(rc != 0 and 'UNAVAILABLE' in err, f'a node that is not there: {err.strip()[-200:]}')
    rc, _, err = h.vpm('bob', 'pacs', 'search', '--endpoint', 'pacs')
    t.check(rc != 0 and 'PERMISSION_DENIED' in err, 'bob may not use the endpoint')
    t.check(h.server_alive(), 'the server keeps serving')


def privacy_checks(h, t, audit):
    """No patient identifier in the server's log or the audit log; the
    audit log records the DIMSE actions."""
    with open(h.server_log) as f:
        log = f.read()
    with open(audit) as f:
        audit_text = f.read()
    secrets = [PATIENT_NAME, 'DIMSE^', PATIENT_ID, BIRTH_DATE, ORTHANC_PASSWORD]
    t.check(not any(s in log for s in secrets) and not any(s in audit_text for s in secrets),
            'neither the server log nor the audit log holds a patient name, ID or birth date')
    actions = {(r['user'], r['action'], r['endpoint'], r['result']) for r in audit_records(audit)}
    t.check({('alice', 'search', 'pacs', 'OK'), ('alice', 'series', 'pacs', 'OK'),
             ('alice', 'open', 'pacs', 'OK'), ('alice', 'export', 'pacs', 'OK'),
             ('alice', 'search', 'wrong-aet', 'PERMISSION_DENIED'),
             ('bob', 'search', 'pacs', 'PERMISSION_DENIED'), ('alice', 'thumbnail', 'pacs', 'OK'),
             ('alice', 'thumbnail', 'pacs', 'INVALID_ARGUMENT')} <= actions,
            'the audit log records the DIMSE actions')


def export_back(h, t, vol):
    session, err = h.vpm_json('alice', 'session', 'open', '--volume-id', vol.get('volume_id', 'x'))
    sid = (session or {}).get('session_id', 'x')
    rc1, _, _ = h.vpm('alice', 'manipulate', '--session', sid, '--grab', '79', '-125.3', '358.3')
    rc2, _, _ = h.vpm('alice', 'manipulate', '--session', sid, '--drag', '0', '0', '15')
    summary, err = h.vpm_json('alice', 'export-dicom', '--session', sid, '--to', 'pacs:pacs', '--json')
    t.check(rc1 == 0 and rc2 == 0 and summary is not None and summary['instances'] == 113 and
            summary['study_uid'] == STUDY, f'export by C-STORE: 113 instances ({err.strip()[-200:]})')
    listed, _ = h.vpm_json('alice', 'pacs', 'series', '--endpoint', 'pacs', '--study', STUDY, '--json')
    by_uid = {s['series_uid']: s for s in (listed or {}).get('series', [])}
    derived = by_uid.get((summary or {}).get('derived_series_uid', 'x'), {})
    t.check(derived.get('modality') == 'CT' and derived.get('instance_count') == 112,
            'C-FIND finds the derived series (112 CT) in the study')


if __name__ == '__main__':
    sys.exit(main())
