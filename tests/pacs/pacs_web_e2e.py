#!/usr/bin/env python3
"""The PACS flow end to end in a browser (issue 27, point 8), on loopback.

Debian's Orthanc with its DICOMweb and GDCM plugins and authentication on
(pacs_harness.py) holds the kidney CT of tests/data, written as a DICOM
series by vpm_test_write_dicom_series, and a structured report in the same
study. vpm-server runs with --pacs (an endpoint only alice may use),
--pacs-audit-log and the users alice and bob; pacs_web_e2e.mjs starts the
gateway and drives headless Chromium: alice searches, lists the series, is
told the SR holds no images, opens the CT, drags the kidney and exports to
PACS, then opens a series of two echoes and picks the second in the Stack
picker; bob has no endpoint and is refused alice's series. Then, here: Orthanc
itself (QIDO-RS with its own credentials) holds the derived series (CT, 112
instances, "vpm deformed ...") and the secondary capture (1 instance) in
the study, and no patient name, ID or birth date is in the gateway's log,
the server's log or the audit log.

Fails (never skips) when Orthanc, node, chromium or the gateway's npm
packages are missing. On failure the temporary folder is kept: logs, the
page's screenshots (failure_*.png).

Usage: pacs_web_e2e.py BUILD_DIR SOURCE_DIR
"""
import json
import os
import shutil
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pacs_harness import Failures, Harness  # noqa: E402

STUDY = '1.2.826.0.1.3680043.8.498.77020'
CT_SERIES = STUDY + '.1'
SR_SERIES = STUDY + '.9'
ECHO_SERIES = STUDY + '.5'
ECHO_OFFSET = 100  # echo 2's stored values = echo 1's + this
PATIENT_NAME = 'KIDNEY^WEBPATIENT'
PATIENT_ID = 'VPMWEB0027'
BIRTH_DATE = '19650704'
STUDY_DATE = '20240315'
ORTHANC_PASSWORD = 'orthanc-pw-web-7d21'
# The left kidney in the written series' world frame (LPS, mm), as
# pacs_orthanc_test grabs it.
KIDNEY_LPS_MM = [79, -125.3, 358.3]
NODE_TIMEOUT_S = 200


def missing_tools(source):
    """What the browser half needs and is not installed, as messages."""
    missing = []
    if not shutil.which('node'):
        missing.append('node is not installed: run scripts/install-deps.sh')
    chromium = os.environ.get('VPM_CHROMIUM', '/usr/bin/chromium')
    if not os.access(chromium, os.X_OK):
        missing.append(f'{chromium} is missing: run scripts/install-deps.sh (Debian\'s chromium)')
    for package in ('playwright-core', 'ws'):
        if not os.path.isdir(os.path.join(source, 'client', 'web', 'node_modules', package)):
            missing.append(f'client/web/node_modules/{package} is missing: run scripts/install-web.sh')
    return missing


def tag(dataset, key):
    """The first value of DICOM JSON attribute `key` (e.g. '00080060'), or None."""
    values = dataset.get(key, {}).get('Value', [])
    return values[0] if values else None


def check_orthanc(h, t, summary):
    """Orthanc itself lists the exported series in the study (QIDO-RS)."""
    listed = h.orthanc_get(f'/dicom-web/studies/{STUDY}/series', 'vpm', ORTHANC_PASSWORD)
    by_uid = {tag(s, '0020000E'): s for s in listed}
    derived = by_uid.get(summary['derived_series_uid'], {})
    capture = by_uid.get(summary['capture_series_uid'], {})
    description = tag(derived, '0008103E') or ''
    t.check(tag(derived, '00080060') == 'CT' and tag(derived, '00201209') == 112 and
            description.startswith('vpm deformed'),
            f'Orthanc holds the derived series in the study: CT, {tag(derived, "00201209")} '
            f'instances, "{description}"')
    t.check(tag(capture, '00201209') == 1,
            f'Orthanc holds the secondary capture in the study: {tag(capture, "00201209")} instance '
            f'({tag(capture, "00080060")}, "{tag(capture, "0008103E")}")')
    t.check(len(listed) == 5 and CT_SERIES in by_uid and SR_SERIES in by_uid,
            f'the study now has 5 series, the source CT and SR among them ({len(listed)})')


def check_logs(h, t, gateway_log, audit):
    """No patient identifier (nor a token or the PACS password) in any log."""
    family, given = PATIENT_NAME.split('^')
    secrets = [PATIENT_NAME, family, given, PATIENT_ID, BIRTH_DATE, ORTHANC_PASSWORD,
               h.tokens['alice'], h.tokens['bob']]
    for name, path in (('the gateway\'s log', gateway_log), ('the server\'s log', h.server_log),
                       ('the audit log', audit)):
        text = open(path).read() if os.path.exists(path) else None
        found = [s for s in secrets if text is not None and s in text]
        t.check(bool(text) and not found,
                f'{name} ({len(text or "")} bytes) holds no patient name, ID, birth date or secret'
                + (f': found {len(found)}' if found else ''))
    records = [json.loads(line) for line in open(audit) if line.strip()]
    actions = {(r['user'], r['action'], r['result']) for r in records}
    t.check({('alice', 'search', 'OK'), ('alice', 'series', 'OK'), ('alice', 'open', 'OK'),
             ('alice', 'export', 'OK'), ('bob', 'search', 'PERMISSION_DENIED'),
             ('bob', 'open', 'PERMISSION_DENIED')} <= actions,
            'the audit log records alice\'s search, listing, open and export and bob\'s refusals')


def run(h, t, build, source):
    kidney, report = h.write_kidney_study(source, STUDY, PATIENT_NAME, PATIENT_ID, BIRTH_DATE,
                                          STUDY_DATE)
    base = h.start_orthanc({'vpm': ORTHANC_PASSWORD})
    # A series of two echoes at the same positions (the tilted Philips CT
    # twice) in the same study: the viewer's Stack picker.
    echoes = h.write_two_echoes(
        os.path.join(source, 'tests/data/ct-philips-tilt'), ECHO_SERIES, ECHO_OFFSET,
        {'StudyInstanceUID': STUDY, 'PatientName': PATIENT_NAME, 'PatientID': PATIENT_ID,
         'PatientBirthDate': BIRTH_DATE, 'StudyDate': STUDY_DATE, 'SeriesNumber': 5,
         'SeriesDescription': 'two echoes'})
    n = h.orthanc_upload_folder(kidney, 'vpm', ORTHANC_PASSWORD)
    n += h.orthanc_upload_folder(report, 'vpm', ORTHANC_PASSWORD)
    n += h.orthanc_upload_folder(echoes, 'vpm', ORTHANC_PASSWORD)
    if not t.check(n == 221, f'Orthanc took {n} instances (112 CT slices, the SR and 108 '
                             'of the two echoes)'):
        return
    h.write_secret('orthanc.pw', ORTHANC_PASSWORD)
    users = h.write_users(['alice', 'bob'])
    with open(users) as f:  # alice may browse the data root (the kidney series' folder)
        lines = f.read().splitlines()
    with open(users, 'w') as f:
        f.write('\n'.join(line + ' browse-data-root' if line.startswith('alice ') else line
                           for line in lines) + '\n')
    endpoints = h.write_endpoints([
        {'name': 'orthanc', 'dicomweb': base, 'username': 'vpm', 'password_file': 'orthanc.pw',
         'users': ['alice']}])
    audit = os.path.join(h.tmp, 'audit.jsonl')
    h.start_server(users, ['--pacs', endpoints, '--pacs-cache', os.path.join(h.tmp, 'cache'),
                           '--pacs-audit-log', audit, '--data-root', os.path.dirname(kidney)])

    config = os.path.join(h.tmp, 'browser.json')
    with open(os.open(config, os.O_WRONLY | os.O_CREAT, 0o600), 'w') as f:
        json.dump({'server': f'127.0.0.1:{h.port}', 'users_file': users, 'tokens': h.tokens,
                   'study_uid': STUDY, 'ct_series_uid': CT_SERIES, 'sr_series_uid': SR_SERIES,
                   'echo_series_uid': ECHO_SERIES, 'echo_offset': ECHO_OFFSET,
                   'data_root_entry': os.path.basename(kidney),
                   'patient': {'name': PATIENT_NAME, 'id': PATIENT_ID, 'birth_date': BIRTH_DATE,
                               'study_date': STUDY_DATE},
                   'kidney_lps_mm': KIDNEY_LPS_MM}, f)
    result = os.path.join(h.tmp, 'browser-result.json')
    started = time.monotonic()
    try:
        p = subprocess.run(['node', os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                 'pacs_web_e2e.mjs'),
                            '--source', source, '--config', config, '--result', result],
                           timeout=NODE_TIMEOUT_S)
        rc = p.returncode
    except subprocess.TimeoutExpired:
        rc = 'timeout'
    t.check(rc == 0 and os.path.exists(result),
            f'the browser flow as alice and bob (pacs_web_e2e.mjs: exit {rc}, '
            f'{time.monotonic() - started:.0f} s)')
    if os.path.exists(result):
        with open(result) as f:
            check_orthanc(h, t, json.load(f)['summary'])
    check_logs(h, t, os.path.join(h.tmp, 'gateway.log'), audit)


def main():
    build, source = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    t = Failures()
    for missing in missing_tools(source):
        t.check(False, missing)
    if t.count:
        return 1
    h = Harness(build)
    started = time.monotonic()
    try:
        run(h, t, build, source)
    except BaseException as e:  # a harness step that ended the test (SystemExit) counts too
        t.check(False, f'{type(e).__name__}: {e}')
    finally:
        h.close(keep=t.count > 0)
    print(f'pacs_web_e2e: {t.count} failure(s) in {time.monotonic() - started:.0f} s')
    return 1 if t.count else 0


if __name__ == '__main__':
    sys.exit(main())
