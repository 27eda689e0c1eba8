#!/usr/bin/env python3
"""vpm against a real PACS: Debian's Orthanc with its DICOMweb and GDCM
plugins, authentication on, loopback only, started here as an unprivileged
process with a temporary configuration and storage.

Loaded into Orthanc by POST /instances: the kidney CT (tests/data's NIfTI,
written as a DICOM CT series by vpm_test_write_dicom_series), a Basic Text
SR in the same study (a non-image series), and the tilted Philips series
of tests/data. Then, through vpm-server --pacs and the `vpm` client:
search by patient-name wildcard, patient ID, date range and modality;
series listing; the library-level check of one retrieved series (every
voxel against the NIfTI, every slice against its ImagePositionPatient);
`vpm volume load pacs:...` with its geometry checked against the slices'
own positions and orientation and its value range against the slices'
pixels; the cache (the second user's open is a cache hit in the audit log,
and still works once Orthanc is stopped); ownership of PACS volumes; the
SR refused with nothing cached; a wrong password; a user the endpoints
file does not allow; Orthanc stopped (UNAVAILABLE, the server keeps
serving); no patient identifier or secret in the server's log or in
errors; the audit log's records.

Usage: pacs_orthanc_test.py BUILD_DIR SOURCE_DIR
"""
import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from pacs_harness import Failures, Harness  # noqa: E402

import numpy  # noqa: E402  (python3-numpy, with python3-pydicom)
import pydicom  # noqa: E402

STUDY = '1.2.826.0.1.3680043.8.498.77010'
CT_SERIES = STUDY + '.1'
SR_SERIES = STUDY + '.9'
PATIENT_NAME = 'KIDNEY^TESTPATIENT'
PATIENT_ID = 'VPMPAT0042'
BIRTH_DATE = '19700101'
ORTHANC_PASSWORD = 'orthanc-pw-5e1f0c'
WRONG_PASSWORD = 'not-the-pw-93ab17'


def slices_geometry(folder):
    """Row, column, normal, the slice positions sorted along the normal,
    pixel spacing and the min/max of the rescaled pixels, from the files."""
    datasets = []
    for name in sorted(os.listdir(folder)):
        try:
            d = pydicom.dcmread(os.path.join(folder, name))
        except pydicom.errors.InvalidDicomError:
            continue  # a README, a licence
        if 'PixelData' in d:
            datasets.append(d)
    iop = numpy.array([float(v) for v in datasets[0].ImageOrientationPatient])
    row, col = iop[:3], iop[3:]
    normal = numpy.cross(row, col)
    positions = sorted((numpy.array([float(v) for v in d.ImagePositionPatient]) for d in datasets),
                       key=lambda p: float(numpy.dot(p, normal)))
    values = [d.pixel_array * float(d.RescaleSlope) + float(d.RescaleIntercept) for d in datasets]
    return dict(row=row, col=col, normal=normal, positions=positions,
                spacing=[float(v) for v in datasets[0].PixelSpacing],
                rows=int(datasets[0].Rows), columns=int(datasets[0].Columns),
                min=float(min(v.min() for v in values)), max=float(max(v.max() for v in values)))


EXPORTED = {'session': 'none'}


def thumbnail_checks(h, t, endpoint, study, series, sr_series, how):
    """`vpm pacs thumbnail` of `series` (a CT) at 96 pixels: a PNG of that
    size, not blank; again (from memory); at the default 128 (the kidney's
    slices are 122 pixels wide: kept at their size); the SR series answers
    INVALID_ARGUMENT. Returns the seconds of the first and of the second."""
    from PIL import Image
    out = os.path.join(h.tmp, f'thumb-{endpoint}.png')
    args = ['pacs', 'thumbnail', '--endpoint', endpoint, '--study', study, '--out', out]
    start = time.monotonic()
    rc, _, err = h.vpm('alice', *args, '--series', series, '--size', '96')
    first_s = time.monotonic() - start
    ok = rc == 0 and os.path.exists(out)
    image = numpy.asarray(Image.open(out).convert('L'), dtype=float) if ok else numpy.zeros((1, 1))
    t.check(ok and max(image.shape) == 96 and image.std() > 20,
            f'a 96-pixel thumbnail of the CT by {how}: {image.shape[1]} x {image.shape[0]}, '
            f'std {image.std():.1f} of 255 ({err.strip()[-200:]})')
    start = time.monotonic()
    rc, _, _ = h.vpm('alice', *args, '--series', series, '--size', '96')
    again_s = time.monotonic() - start
    rc2, _, err = h.vpm('alice', *args, '--series', series)
    size = Image.open(out).size if rc2 == 0 else (0, 0)
    t.check(rc == 0 and rc2 == 0 and 96 < max(size) <= 128,
            f'again, and at the default 128 pixels: {size} (the slices are smaller)')
    rc, _, err = h.vpm('alice', *args, '--series', sr_series)
    t.check(rc != 0 and 'INVALID_ARGUMENT' in err and 'no image' in err,
            f'the SR has no thumbnail: {err.strip()[-200:]}')
    print(f'      figures: thumbnail by {how} {first_s:.2f} s (vpm process included), '
          f'again {again_s:.2f} s')
    return first_s, again_s


def dciodvfy_errors(folder):
    """The 'Error' lines dciodvfy reports over every file of `folder`, and
    the distinct report lines (for the note)."""
    import subprocess
    errors, lines = [], set()
    for name in sorted(os.listdir(folder)):
        p = subprocess.run(['dciodvfy', os.path.join(folder, name)], capture_output=True, text=True)
        for line in (p.stdout + p.stderr).splitlines():
            lines.add(line)
            if line.startswith('Error'):
                errors.append(f'{name}: {line}')
    return errors, sorted(lines)


def export_checks(h, t, vol, study, source_folder, audit):
    """The kidney grabbed and dragged 15 mm superior, exported as a derived
    series: to a folder (dciodvfy, the study's identity, the references) and
    to Orthanc by STOW-RS (found by QIDO in the study, read back by vpm with
    the source's geometry); other users refused."""
    session, err = h.vpm_json('alice', 'session', 'open', '--volume-id', vol.get('volume_id', 'x'))
    sid = (session or {}).get('session_id', 'x')
    EXPORTED['session'] = sid
    rc1, _, e1 = h.vpm('alice', 'manipulate', '--session', sid, '--grab', '79', '-125.3', '358.3')
    rc2, out, e2 = h.vpm('alice', 'manipulate', '--session', sid, '--drag', '0', '0', '15')
    t.check(session is not None and rc1 == 0 and rc2 == 0,
            f'alice grabs the left kidney and drags it 15 mm superior ({(err + e1 + e2).strip()[-200:]})')
    out_dir = os.path.join(h.tmp, 'export')
    summary, err = h.vpm_json('alice', 'export-dicom', '--session', sid, '--out-dir', out_dir, '--json')
    derived = os.path.join(out_dir, 'derived')
    names = sorted(os.listdir(derived)) if os.path.isdir(derived) else []
    t.check(summary is not None and len(names) == 112 and summary['instances'] == 113 and
            summary['study_uid'] == study and summary['max_displacement_mm'] > 10,
            f'export to a folder: 112 slices + 1 capture in the source study, '
            f'{(summary or {}).get("max_displacement_mm", 0):.1f} mm moved ({err.strip()[-200:]})')
    if names:
        derived_series_checks(t, out_dir, study, source_folder, names)
        export_to_orthanc_checks(h, t, vol, study, sid, audit)


def derived_series_checks(t, out_dir, study, source_folder, names):
    """The exported folder: dciodvfy finds no error; the derived series
    keeps the source's study, patient and frame of reference with new UIDs
    and references its source images, on the source grid."""
    derived = os.path.join(out_dir, 'derived')
    errors, lines = dciodvfy_errors(derived)
    cap_errors, cap_lines = dciodvfy_errors(os.path.join(out_dir, 'capture'))
    t.check(not errors and not cap_errors,
            f'dciodvfy: no error in 112 CT images and the secondary capture {(errors + cap_errors)[:3]}')
    print('      dciodvfy (derived CT, distinct lines):', ' | '.join(lines))
    print('      dciodvfy (secondary capture):', ' | '.join(cap_lines))
    first = pydicom.dcmread(os.path.join(derived, names[0]))
    source_files = [pydicom.dcmread(os.path.join(source_folder, n)) for n in sorted(os.listdir(source_folder))]
    source_uids = {d.SOPInstanceUID for d in source_files}
    t.check(first.StudyInstanceUID == study and first.PatientID == PATIENT_ID and
            first.FrameOfReferenceUID == source_files[0].FrameOfReferenceUID and
            list(first.ImageType)[:2] == ['DERIVED', 'SECONDARY'] and
            first.SeriesInstanceUID != CT_SERIES and first.SOPInstanceUID not in source_uids and
            first.SourceImageSequence[0].ReferencedSOPInstanceUID in source_uids and
            'Deformed by vpm' in first.DerivationDescription,
            'the derived series: same study, patient and frame of reference, new UIDs, '
            'DERIVED\\SECONDARY, a source image referenced, what was done described')
    deformed = numpy.stack([pydicom.dcmread(os.path.join(derived, n)).pixel_array for n in names])
    t.check(deformed.shape == (112, 101, 122), f'slices of the source grid {deformed.shape}')


def export_to_orthanc_checks(h, t, vol, study, sid, audit):
    """Session `sid` exported to Orthanc by STOW-RS: QIDO finds both series
    in the study, vpm reads the derived one back on the source grid; bob and
    a forbidden endpoint are refused; the audit log records it."""
    summary, err = h.vpm_json('alice', 'export-dicom', '--session', sid, '--to', 'pacs:orthanc', '--json')
    t.check(summary is not None and summary['endpoint'] == 'orthanc' and summary['instances'] == 113,
            f'export to Orthanc by STOW-RS ({err.strip()[-200:]})')
    if summary is None:
        return
    listed, _ = h.vpm_json('alice', 'pacs', 'series', '--endpoint', 'orthanc', '--study', study, '--json')
    by_uid = {s['series_uid']: s for s in (listed or {}).get('series', [])}
    d = by_uid.get(summary['derived_series_uid'], {})
    c = by_uid.get(summary['capture_series_uid'], {})
    t.check(d.get('modality') == 'CT' and d.get('instance_count') == 112 and
            d.get('description', '').startswith('vpm deformed') and c.get('instance_count') == 1,
            'QIDO finds the derived series (112 CT) and the capture in the study')
    rc, out, err = h.vpm('alice', 'volume', 'load', d.get('source', 'pacs:orthanc/x/y'))
    back = json.loads(out) if rc == 0 else {}
    if back:
        o1, o2 = numpy.array(vol['origin_lps_mm']), numpy.array(back['origin_lps_mm'])
        d1, d2 = numpy.array(vol['direction_columns_lps']), numpy.array(back['direction_columns_lps'])
        s1, s2 = numpy.array(vol['spacing_mm']), numpy.array(back['spacing_mm'])
        corners = [numpy.array([i, j, k]) for i in (0, vol['dims'][0] - 1)
                   for j in (0, vol['dims'][1] - 1) for k in (0, vol['dims'][2] - 1)]
        worst = max(float(numpy.linalg.norm((o1 + d1.T @ (c * s1)) - (o2 + d2.T @ (c * s2))))
                    for c in corners)
        t.check(back['dims'] == vol['dims'] and worst < 1e-3,
                f'vpm reads the exported series back from Orthanc on the source grid '
                f'(geometry error {worst:.2e} mm at the corners)')
        print(f'      figures: exported series geometry error {worst:.2e} mm')
    else:
        t.check(False, f'vpm reads the exported series back ({err.strip()[-200:]})')
    rc, _, err = h.vpm('bob', 'export-dicom', '--session', sid, '--out-dir', os.path.join(h.tmp, 'bob'))
    t.check(rc != 0 and ('NOT_FOUND' in err or 'PERMISSION_DENIED' in err),
            f'bob may not export alice\'s session: {err.strip()[-120:]}')
    rc, _, err = h.vpm('alice', 'export-dicom', '--session', sid, '--to', 'pacs:orthanc-nowhere')
    t.check(rc != 0 and 'PERMISSION_DENIED' in err, 'nor alice to an endpoint she may not use')
    exports = [r for r in audit_records(audit) if r['action'] == 'export']
    t.check(any(r['result'] == 'OK' and r.get('endpoint') == 'orthanc' and
                r['series_uid'] == summary['derived_series_uid'] and r['study_uid'] == study
                for r in exports), 'the audit log records the export with its study and series')


def audit_records(path):
    with open(path) as f:
        return [json.loads(line) for line in f if line.strip()]


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
    tilt_folder = os.path.join(source, 'tests/data/ct-philips-tilt')
    kidney, report = h.write_kidney_study(source, STUDY, PATIENT_NAME, PATIENT_ID, BIRTH_DATE,
                                          '20240315')
    base = h.start_orthanc({'vpm': ORTHANC_PASSWORD})
    n = h.orthanc_upload_folder(kidney, 'vpm', ORTHANC_PASSWORD)
    n += h.orthanc_upload_folder(report, 'vpm', ORTHANC_PASSWORD)
    tilt_n = h.orthanc_upload_folder(tilt_folder, 'vpm', ORTHANC_PASSWORD)
    t.check(n == 113 and tilt_n == 54, f'Orthanc took {n} kidney/SR and {tilt_n} tilted instances')
    echoes = h.write_two_echoes(tilt_folder, ECHO_SERIES, ECHO_OFFSET)
    echo_n = h.orthanc_upload_folder(echoes, 'vpm', ORTHANC_PASSWORD)
    t.check(echo_n == 108, f'Orthanc took {echo_n} instances of the two-echo series')
    live_check(h, t, build, source, base)
    audit, cache = start_server(h, base)
    search_checks(h, t)
    series_checks(h, t, cache)
    vol, bob_vol = load_checks(h, t, kidney, audit, cache)
    tilt_checks(h, t, tilt_folder)
    stack_checks(h, t, tilt_folder)
    export_checks(h, t, vol, STUDY, kidney, audit)
    failure_checks(h, t, cache, bob_vol)
    privacy_checks(h, t, audit)


def live_check(h, t, build, source, base):
    """The library alone (vpm_test_pacs_live_check): every voxel and every
    slice position of the retrieved kidney CT."""
    import subprocess
    checker = os.path.join(build, 'tests', 'pacs', 'vpm_test_pacs_live_check')
    kidney_nifti = os.path.join(source, 'tests/data/ct-abdomen-kidney/ct_abdomen.nii.gz')
    pw_file = h.write_secret('orthanc.pw', ORTHANC_PASSWORD)
    p = subprocess.run([checker, '--url', base, '--username', 'vpm', '--password-file', pw_file,
                        '--study', STUDY, '--series', CT_SERIES, '--source', kidney_nifti,
                        '--cache', os.path.join(h.tmp, 'live-cache')],
                       capture_output=True, text=True)
    print('      live check:', p.stdout.strip(), p.stderr.strip())
    t.check(p.returncode == 0, 'vpm_pacs retrieves the kidney CT: every voxel equals the NIfTI, '
                               'every slice lies at its ImagePositionPatient')


def start_server(h, base):
    """vpm-server with alice, bob and carol, the endpoints file (orthanc for
    alice and bob, orthanc-badpw for alice), a PACS cache and an audit log.
    Returns the audit log's and the cache's paths."""
    h.write_secret('wrong.pw', WRONG_PASSWORD)
    users = h.write_users(['alice', 'bob', 'carol'])
    endpoints = h.write_endpoints([
        {'name': 'orthanc', 'dicomweb': base, 'username': 'vpm', 'password_file': 'orthanc.pw',
         'users': ['alice', 'bob']},
        {'name': 'orthanc-badpw', 'dicomweb': base, 'username': 'vpm', 'password_file': 'wrong.pw',
         'users': ['alice']}])
    audit = os.path.join(h.tmp, 'audit.jsonl')
    cache = os.path.join(h.tmp, 'cache')
    h.start_server(users, ['--pacs', endpoints, '--pacs-cache', cache, '--pacs-audit-log', audit])
    return audit, cache


def search_checks(h, t):
    """`vpm pacs search` by name wildcard, ID, date range, modality and
    limit; a forbidden user and an unknown endpoint get the same answer."""
    found, err = h.vpm_json('alice', 'pacs', 'search', '--endpoint', 'orthanc',
                            '--patient-name', 'KIDNEY^TEST*', '--json')
    studies = (found or {}).get('studies', [])
    t.check(len(studies) == 1 and studies[0]['study_uid'] == STUDY and
            studies[0]['patient_id'] == PATIENT_ID and studies[0]['patient_birth_date'] == BIRTH_DATE,
            f'search by patient-name wildcard finds the kidney study ({err.strip()})')
    t.check(bool(studies) and set(studies[0]['modalities']) >= {'CT', 'SR'} and
            studies[0]['series_count'] == 2, 'the study lists CT and SR, 2 series')
    found, _ = h.vpm_json('alice', 'pacs', 'search', '--endpoint', 'orthanc', '--patient-id',
                          PATIENT_ID, '--study-date', '20240101-20241231', '--modality', 'CT', '--json')
    t.check([s['study_uid'] for s in (found or {}).get('studies', [])] == [STUDY],
            'search by patient ID, study-date range and modality')
    found, _ = h.vpm_json('alice', 'pacs', 'search', '--endpoint', 'orthanc', '--patient-id',
                          PATIENT_ID, '--study-date', '20250101-', '--json')
    t.check(found is not None and found['studies'] == [], 'a date range after the study finds nothing')
    everything, _ = h.vpm_json('alice', 'pacs', 'search', '--endpoint', 'orthanc', '--json')
    t.check(everything is not None and len(everything['studies']) == 2,
            'an empty search lists both studies')
    limited, _ = h.vpm_json('alice', 'pacs', 'search', '--endpoint', 'orthanc', '--limit', '1', '--json')
    t.check(limited is not None and len(limited['studies']) == 1 and limited['truncated'],
            '--limit 1 answers one study, truncated')
    rc, out, _ = h.vpm('alice', 'pacs', 'search', '--endpoint', 'orthanc', '--patient-name', 'KIDNEY*')
    t.check(rc == 0 and PATIENT_NAME in out and '1 studies' in out, 'the text table of a search')
    rc, _, err = h.vpm('carol', 'pacs', 'search', '--endpoint', 'orthanc')
    t.check(rc != 0 and 'PERMISSION_DENIED' in err, f'a user the file does not allow is refused: {err.strip()}')
    rc, _, err2 = h.vpm('alice', 'pacs', 'search', '--endpoint', 'nowhere')
    t.check(rc != 0 and 'PERMISSION_DENIED' in err2 and
            err2.replace('nowhere', 'orthanc') == err.replace('carol', 'alice'),
            'an unknown endpoint gets the same answer as a forbidden one')


def series_checks(h, t, cache):
    """`vpm pacs series` of the study, and the CT's thumbnails."""
    listed, err = h.vpm_json('alice', 'pacs', 'series', '--endpoint', 'orthanc', '--study', STUDY, '--json')
    series = (listed or {}).get('series', [])
    ct = [s for s in series if s['series_uid'] == CT_SERIES]
    t.check(len(series) == 2 and len(ct) == 1 and ct[0]['modality'] == 'CT' and
            ct[0]['instance_count'] == 112 and ct[0]['body_part'] == 'ABDOMEN' and
            ct[0]['description'] == 'Abdomen 3mm' and
            ct[0]['source'] == f'pacs:orthanc/{STUDY}/{CT_SERIES}',
            f'series listing: modality, description, body part, 112 images ({err.strip()})')
    rc, out, _ = h.vpm('alice', 'pacs', 'series', '--endpoint', 'orthanc', '--study', STUDY)
    t.check(rc == 0 and f'pacs:orthanc/{STUDY}/{CT_SERIES}' in out, 'the text table of a listing')
    thumbnail_checks(h, t, 'orthanc', STUDY, CT_SERIES, SR_SERIES, 'WADO-RS')
    rc, _, err = h.vpm('carol', 'pacs', 'thumbnail', '--endpoint', 'orthanc', '--study', STUDY,
                       '--series', CT_SERIES, '--out', os.path.join(h.tmp, 'carol.png'))
    t.check(rc != 0 and 'PERMISSION_DENIED' in err, 'carol may not see a thumbnail')
    t.check(not [n for n in os.listdir(cache) if n.startswith('.tmp-')],
            'no scratch folder of a thumbnail is left in the cache')


def volume_geometry_checks(t, vol, g, ct_source):
    """The volume vpm opened (`vpm volume load`'s JSON) against the slices'
    geometry g (slices_geometry): dims, direction, spacing, every slice's
    position, the value range, the owner."""
    direction = numpy.array(vol['direction_columns_lps'])  # rows: the i, j, k axes
    origin = numpy.array(vol['origin_lps_mm'])
    spacing = vol['spacing_mm']
    gap = float(numpy.dot(g['positions'][1] - g['positions'][0], g['normal']))
    t.check(vol['dims'] == [g['columns'], g['rows'], len(g['positions'])],
            f'dims {vol["dims"]} = columns, rows, slices')
    t.check(numpy.allclose(direction[0], g['row'], atol=1e-6) and
            numpy.allclose(direction[1], g['col'], atol=1e-6) and
            numpy.allclose(direction[2], g['normal'], atol=1e-6),
            'direction = ImageOrientationPatient and its normal')
    t.check(abs(spacing[0] - g['spacing'][1]) < 1e-6 and abs(spacing[1] - g['spacing'][0]) < 1e-6
            and abs(spacing[2] - gap) < 1e-4, f'spacing {spacing} = PixelSpacing and the gap')
    worst = max(float(numpy.linalg.norm(origin + direction[2] * spacing[2] * k - p))
                for k, p in enumerate(g['positions']))
    t.check(worst < 1e-3, f'every slice k at origin + k gap normal = its ImagePositionPatient '
                          f'(worst {worst:.2e} mm)')
    t.check(vol['min_value'] == g['min'] and vol['max_value'] == g['max'],
            f'values {vol["min_value"]}..{vol["max_value"]} = the slices\' {g["min"]}..{g["max"]}')
    t.check(vol['owner'] == 'alice' and vol['source'] == ct_source, 'the volume is alice\'s')


def load_checks(h, t, kidney, audit, cache):
    """alice opens the kidney CT from Orthanc (its geometry and values
    against the slices' own), bob from the cache, alice again (held); bob
    can neither read nor list alice's volume. Returns both volumes."""
    ct_source = f'pacs:orthanc/{STUDY}/{CT_SERIES}'
    start = time.monotonic()
    rc, out, err = h.vpm('alice', 'volume', 'load', ct_source)
    first_s = time.monotonic() - start
    vol = json.loads(out) if rc == 0 else {}
    t.check(rc == 0, f'vpm volume load {ct_source} ({err.strip()[-300:]})')
    if vol:
        volume_geometry_checks(t, vol, slices_geometry(kidney), ct_source)
    records = audit_records(audit)
    opens = [r for r in records if r['action'] == 'open']
    t.check(len(opens) == 1 and opens[0]['cache'] == 'miss' and opens[0]['result'] == 'OK' and
            opens[0]['instances'] == 112, 'the first open is a cache miss of 112 instances')
    t.check(os.path.isdir(os.path.join(cache, 'orthanc', CT_SERIES)) and
            not [n for n in os.listdir(cache) if n.startswith('.tmp-')],
            'the series is in the cache, whole, with no temporary folder left')

    start = time.monotonic()
    rc, out, err = h.vpm('bob', 'volume', 'load', ct_source)
    second_s = time.monotonic() - start
    bob_vol = json.loads(out) if rc == 0 else {}
    opens = [r for r in audit_records(audit) if r['action'] == 'open']
    t.check(rc == 0 and bob_vol.get('owner') == 'bob' and bob_vol.get('volume_id') != vol.get('volume_id')
            and bob_vol.get('min_value') == vol.get('min_value'),
            'bob opens the same series as a volume of his own')
    t.check(len(opens) == 2 and opens[1]['cache'] == 'hit' and opens[1]['user'] == 'bob',
            'bob\'s open is a cache hit (no second retrieval)')
    start = time.monotonic()
    rc, out, _ = h.vpm('alice', 'volume', 'load', ct_source)
    held_s = time.monotonic() - start
    opens = [r for r in audit_records(audit) if r['action'] == 'open']
    t.check(rc == 0 and json.loads(out)['volume_id'] == vol.get('volume_id') and
            opens[-1]['cache'] == 'held', 'alice loading again gets her volume (audited as held)')
    rc, _, err = h.vpm('bob', 'volume', 'get', vol.get('volume_id', 'x'))
    t.check(rc != 0 and 'NOT_FOUND' in err,
            'bob may not read alice\'s PACS volume (told it is not there, as for a missing id)')
    listed, _ = h.vpm_json('bob', 'volume', 'list')
    t.check(listed is not None and vol.get('volume_id') not in [v['volume_id'] for v in listed],
            'nor see it listed')
    print(f'      figures: first open {first_s:.2f} s (retrieve + read + GPU upload), '
          f'second user from the cache {second_s:.2f} s, held {held_s:.2f} s')
    return vol, bob_vol


def tilt_checks(h, t, tilt_folder):
    """The tilted series: retrieved, resampled, every slice inside the box."""
    tilt = pydicom.dcmread(os.path.join(tilt_folder, 'I10'))
    tilt_source = f'pacs:orthanc/{tilt.StudyInstanceUID}/{tilt.SeriesInstanceUID}'
    rc, out, err = h.vpm('alice', 'volume', 'load', tilt_source)
    tv = json.loads(out) if rc == 0 else {}
    t.check(rc == 0 and any('tilt' in n for n in tv.get('notes', [])),
            f'the tilted Philips series loads from Orthanc, resampled ({err.strip()[-200:]})')
    if tv:
        tg = slices_geometry(tilt_folder)
        d = numpy.array(tv['direction_columns_lps'])
        o = numpy.array(tv['origin_lps_mm'])
        idx = [numpy.dot(d, p - o) / numpy.array(tv['spacing_mm']) for p in tg['positions']]
        inside = all(-0.5 <= i[c] <= tv['dims'][c] - 0.5 for i in idx for c in range(3))
        t.check(inside, 'every tilted slice\'s ImagePositionPatient lies inside the volume\'s grid')


# The two-echo series write_two_echoes makes of the tilted series.
ECHO_SERIES = '1.2.826.0.1.3680043.8.498.77031'
ECHO_OFFSET = 100  # echo 2's stored values = echo 1's + this


def stack_checks(h, t, tilt_folder):
    """A series of two echoes from the PACS: the first stack by default,
    ?stack=2 the second (from the same cached files), ?stack=3 refused."""
    study = pydicom.dcmread(os.path.join(tilt_folder, 'I10')).StudyInstanceUID
    source = f'pacs:orthanc/{study}/{ECHO_SERIES}'
    rc, out, err = h.vpm('alice', 'volume', 'load', source)
    first = json.loads(out) if rc == 0 else {}
    t.check(rc == 0 and first.get('stacks') == ['EchoNumbers 1', 'EchoNumbers 2'] and
            first.get('stack') == 1 and any('read stack 1' in n for n in first.get('notes', [])),
            f'the two-echo series opens on echo 1 and names both: {first.get("stacks")}, '
            f'{first.get("stack")} ({err.strip()[-200:]})')
    rc, out, err = h.vpm('alice', 'volume', 'load', source + '?stack=2')
    second = json.loads(out) if rc == 0 else {}
    t.check(rc == 0 and second.get('stack') == 2 and second.get('source') == source + '?stack=2' and
            abs(second.get('max_value', 0) - first.get('max_value', 0) - ECHO_OFFSET) < 0.01,
            f'?stack=2 opens echo 2: stack {second.get("stack")}, max {second.get("max_value")} '
            f'against echo 1\'s {first.get("max_value")} ({err.strip()[-200:]})')
    rc, _, err = h.vpm('alice', 'volume', 'load', source + '?stack=3')
    t.check(rc != 0 and 'INVALID_ARGUMENT' in err and 'holds 2 stacks' in err and
            'EchoNumbers 2' in err, f'?stack=3 is refused, naming the stacks: {err.strip()[-200:]}')


def failure_checks(h, t, cache, bob_vol):
    """An SR, an unknown series, a wrong password, a forbidden user; then
    Orthanc stopped: UNAVAILABLE, the cache still serves, the server lives."""
    ct_source = f'pacs:orthanc/{STUDY}/{CT_SERIES}'
    rc, _, err = h.vpm('alice', 'volume', 'load', f'pacs:orthanc/{STUDY}/{SR_SERIES}')
    t.check(rc != 0 and 'INVALID_ARGUMENT' in err and 'holds no images' in err,
            f'the structured report is refused: {err.strip()[-200:]}')
    t.check(not os.path.exists(os.path.join(cache, 'orthanc', SR_SERIES)) and
            not [n for n in os.listdir(cache) if n.startswith('.tmp-')], 'and nothing of it is cached')
    rc, _, err = h.vpm('alice', 'volume', 'load', f'pacs:orthanc/{STUDY}/{STUDY}.555')
    t.check(rc != 0 and 'NOT_FOUND' in err, f'an unknown series is NOT_FOUND: {err.strip()[-160:]}')
    rc, _, err = h.vpm('alice', 'pacs', 'search', '--endpoint', 'orthanc-badpw', '--patient-name', 'K*')
    t.check(rc != 0 and 'PERMISSION_DENIED' in err and 'credentials' in err and
            WRONG_PASSWORD not in err, f'a wrong password: {err.strip()}')
    rc, _, err = h.vpm('carol', 'volume', 'load', ct_source)
    t.check(rc != 0 and 'PERMISSION_DENIED' in err, 'carol may not pull from the PACS')

    h.stop_orthanc()
    rc, _, err = h.vpm('alice', 'pacs', 'search', '--endpoint', 'orthanc')
    t.check(rc != 0 and 'UNAVAILABLE' in err, f'Orthanc stopped: search is UNAVAILABLE: {err.strip()}')
    rc, _, err = h.vpm('alice', 'volume', 'load', f'pacs:orthanc/{STUDY}/{SR_SERIES}')
    t.check(rc != 0 and 'UNAVAILABLE' in err, 'and an uncached series is UNAVAILABLE')
    rc, _, _ = h.vpm('bob', 'volume', 'delete', bob_vol.get('volume_id', 'x'))
    rc2, out, err = h.vpm('bob', 'volume', 'load', ct_source)
    t.check(rc == 0 and rc2 == 0, f'a cached series still opens with Orthanc down ({err.strip()[-160:]})')
    rc, _, err = h.vpm('alice', 'export-dicom', '--session', EXPORTED['session'], '--to', 'pacs:orthanc')
    t.check(rc != 0 and 'UNAVAILABLE' in err, f'an export to the stopped Orthanc is UNAVAILABLE: {err.strip()[-200:]}')
    rc, _, _ = h.vpm('alice', 'volume', 'list')
    t.check(rc == 0 and h.server_alive(), 'the server keeps serving')


def privacy_checks(h, t, audit):
    """No patient identifier or secret in the server's log or the audit log;
    the audit log records every action with its fields."""
    with open(h.server_log) as f:
        log = f.read()
    secrets = [PATIENT_NAME, 'KIDNEY', PATIENT_ID, BIRTH_DATE, ORTHANC_PASSWORD, WRONG_PASSWORD]
    t.check(not any(s in log for s in secrets),
            'the server log holds no patient name, ID, birth date or password')
    with open(audit) as f:
        text = f.read()
    records = audit_records(audit)
    t.check(not any(s in text for s in secrets), 'neither does the audit log')
    keys = {'time', 'user', 'action', 'endpoint', 'study_uid', 'series_uid', 'result'}
    t.check(all(keys <= set(r) for r in records),
            f'every audit record has time, user, action, UIDs, result ({len(records)})')
    actions = {(r['user'], r['action'], r['result']) for r in records}
    t.check({('alice', 'search', 'OK'), ('carol', 'search', 'PERMISSION_DENIED'),
             ('alice', 'series', 'OK'), ('alice', 'open', 'OK'), ('bob', 'open', 'OK'),
             ('alice', 'open', 'INVALID_ARGUMENT'), ('alice', 'search', 'UNAVAILABLE'),
             ('carol', 'open', 'PERMISSION_DENIED'), ('alice', 'export', 'OK'),
             ('alice', 'export', 'UNAVAILABLE'), ('alice', 'thumbnail', 'OK'),
             ('alice', 'thumbnail', 'INVALID_ARGUMENT'),
             ('carol', 'thumbnail', 'PERMISSION_DENIED')} <= actions,
            'the audit log records every action')
    exports = [r for r in records if r['action'] == 'export' and r['result'] == 'OK']
    if exports:
        print('      audit excerpt (export):', json.dumps(exports[0]))
    print('      audit excerpt:', json.dumps(records[0]))


if __name__ == '__main__':
    sys.exit(main())
