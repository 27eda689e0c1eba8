"""What the PACS test scripts share: free ports, a vpm-server with users
and a --pacs file, the `vpm` client, and Debian's Orthanc as an
unprivileged process on loopback.

Nothing here downloads anything; every process started is stopped by
Harness.close() (the scripts call it in a finally block).
"""
import hashlib
import json
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time
import urllib.error
import urllib.request
import base64

ORTHANC = '/usr/sbin/Orthanc'
ORTHANC_PLUGINS = ['/usr/share/orthanc/plugins/libOrthancDicomWeb.so',
                   '/usr/share/orthanc/plugins/libOrthancGdcm.so']


def free_port():
    with socket.socket() as s:
        s.bind(('127.0.0.1', 0))
        return s.getsockname()[1]


class Failures:
    def __init__(self):
        self.count = 0

    def check(self, condition, what):
        print(('ok:   ' if condition else 'FAIL: ') + what, flush=True)
        if not condition:
            self.count += 1
        return condition


class Harness:
    def __init__(self, build_dir):
        self.build = os.path.abspath(build_dir)
        self.server_bin = os.path.join(self.build, 'server', 'service', 'vpm-server')
        self.vpm_bin = os.path.join(self.build, 'client', 'vpm')
        for b in (self.server_bin, self.vpm_bin):
            if not os.access(b, os.X_OK):
                raise SystemExit(f'FAIL: {b} is not built')
        self.tmp = tempfile.mkdtemp(prefix='vpm-pacs-test-')
        self.procs = []
        self.server = None
        self.port = None
        self.tokens = {}

    # ----------------------------------------------------------- vpm-server
    def write_users(self, names):
        lines = []
        for name in names:
            token = hashlib.sha256(f'{name}-{self.tmp}'.encode()).hexdigest()[:32]
            self.tokens[name] = token
            lines.append(f'{name} {hashlib.sha256(token.encode()).hexdigest()}')
        path = os.path.join(self.tmp, 'users.txt')
        with open(path, 'w') as f:
            f.write('\n'.join(lines) + '\n')
        return path

    def write_secret(self, name, text):
        path = os.path.join(self.tmp, name)
        with open(path, 'w') as f:
            f.write(text + '\n')
        os.chmod(path, 0o600)
        return path

    def write_endpoints(self, endpoints):
        path = os.path.join(self.tmp, 'pacs.json')
        with open(path, 'w') as f:
            json.dump(endpoints, f)
        return path

    def start_server(self, users_file, extra):
        self.server_log = os.path.join(self.tmp, 'server.log')
        log = open(self.server_log, 'w')
        self.server = subprocess.Popen(
            [self.server_bin, '--listen', '127.0.0.1:0', '--users', users_file,
             '--shutdown-grace-s', '2'] + extra, stdout=log, stderr=subprocess.STDOUT)
        self.procs.append(self.server)
        for _ in range(600):
            with open(self.server_log) as f:
                for line in f:
                    if line.startswith('vpm-server listening on port '):
                        self.port = int(line.split()[4])
                        return
            if self.server.poll() is not None:
                raise SystemExit('FAIL: vpm-server exited at start:\n' + open(self.server_log).read())
            time.sleep(0.1)
        raise SystemExit('FAIL: vpm-server did not start')

    def vpm(self, user, *args, timeout=300):
        """Runs `vpm --server ... --token ... ARGS`; returns (rc, stdout, stderr)."""
        env = dict(os.environ, VPM_TOKEN=self.tokens[user])
        cmd = [self.vpm_bin, '--server', f'127.0.0.1:{self.port}'] + list(args)
        p = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=timeout)
        return p.returncode, p.stdout, p.stderr

    def vpm_json(self, user, *args):
        rc, out, err = self.vpm(user, *args)
        if rc != 0:
            return None, err
        return json.loads(out), err

    def server_alive(self):
        return self.server is not None and self.server.poll() is None

    # -------------------------------------------------------------- Orthanc
    def write_kidney_study(self, source, study, patient_name, patient_id, birth_date,
                           study_date):
        """The kidney CT of tests/data (series STUDY.1, "Abdomen 3mm") and a
        structured report (STUDY.9) in one study, as two folders of DICOM
        files under the temp folder; returns (kidney folder, report folder)."""
        writer = os.path.join(self.build, 'tests', 'pacs', 'vpm_test_write_dicom_series')
        kidney = os.path.join(self.tmp, 'kidney')
        report = os.path.join(self.tmp, 'report')
        common = ['--study-uid', study, '--patient-name', patient_name, '--patient-id', patient_id,
                  '--birth-date', birth_date, '--study-date', study_date]
        subprocess.run([writer, os.path.join(source, 'tests/data/ct-abdomen-kidney/ct_abdomen.nii.gz'),
                        kidney, '--series-uid', study + '.1', '--series-number', '2',
                        '--description', 'Abdomen 3mm'] + common, check=True, capture_output=True)
        subprocess.run([writer, '--structured-report', report, '--series-uid', study + '.9',
                        '--series-number', '9', '--description', 'Report'] + common,
                       check=True, capture_output=True)
        return kidney, report

    def start_orthanc(self, users, dimse=False, modalities=None):
        """Orthanc with authentication on, loopback HTTP only, storage in the
        temp folder. The DICOM server is off unless `dimse`: then Orthanc is
        the node ORTHANC@127.0.0.1:self.orthanc_dicom_port, checks the AE
        title it is called by, and knows vpm as the modality VPM (C-FIND,
        C-GET, C-STORE). `modalities` replaces the nodes Orthanc knows
        ({'vpm': ['VPM', '127.0.0.1', PORT]}: vpm's --dicom-listen node, for
        C-MOVE and POST /modalities/vpm/store). Returns the DICOMweb base URL."""
        if not os.access(ORTHANC, os.X_OK):
            raise SystemExit(f'FAIL: {ORTHANC} is not installed (scripts/install-deps.sh)')
        root = os.path.join(self.tmp, 'orthanc')
        os.makedirs(root, exist_ok=True)
        self.orthanc_port = free_port()
        self.orthanc_dicom_port = free_port()
        self.orthanc_users = users
        config = {
            'Name': 'vpm-pacs-test',
            'StorageDirectory': os.path.join(root, 'storage'),
            'IndexDirectory': os.path.join(root, 'index'),
            'HttpPort': self.orthanc_port,
            'DicomPort': self.orthanc_dicom_port,
            'DicomServerEnabled': dimse,
            'DicomAet': 'ORTHANC',
            'DicomCheckCalledAet': True,
            'DicomModalities': modalities or {'vpm': ['VPM', '127.0.0.1', 1]},
            'RemoteAccessAllowed': False,
            'AuthenticationEnabled': True,
            'RegisteredUsers': users,
            'Plugins': ORTHANC_PLUGINS,
            'DicomWeb': {'Enable': True, 'Root': '/dicom-web/'},
            'HttpThreadsCount': 8,
            'SaveJobs': False,
        }
        path = os.path.join(root, 'orthanc.json')
        with open(path, 'w') as f:
            json.dump(config, f)
        self.orthanc_log = os.path.join(root, 'orthanc.log')
        log = open(self.orthanc_log, 'w')
        self.orthanc = subprocess.Popen([ORTHANC, path], stdout=log, stderr=subprocess.STDOUT,
                                        start_new_session=True)
        self.procs.append(self.orthanc)
        user, password = next(iter(users.items()))
        for _ in range(300):
            try:
                self.orthanc_get('/system', user, password)
                return f'http://127.0.0.1:{self.orthanc_port}/dicom-web'
            except (urllib.error.URLError, ConnectionError):
                if self.orthanc.poll() is not None:
                    raise SystemExit('FAIL: Orthanc exited at start:\n' + open(self.orthanc_log).read())
                time.sleep(0.1)
        raise SystemExit('FAIL: Orthanc did not start')

    def orthanc_request(self, method, path, user, password, data=None,
                        content_type='application/dicom'):
        req = urllib.request.Request(f'http://127.0.0.1:{self.orthanc_port}{path}', data=data,
                                     method=method)
        token = base64.b64encode(f'{user}:{password}'.encode()).decode()
        req.add_header('Authorization', f'Basic {token}')
        if data is not None:
            req.add_header('Content-Type', content_type)
        with urllib.request.urlopen(req, timeout=30) as r:
            return json.loads(r.read() or b'null')

    def orthanc_get(self, path, user, password):
        return self.orthanc_request('GET', path, user, password)

    def write_two_echoes(self, folder, series_uid, offset, tags=None):
        """The image series in `folder` twice under one new SeriesInstanceUID,
        as a scanner stores the echoes of an in/opposed-phase T1: EchoNumbers
        1 and 2 at the same positions, echo 2's stored values `offset`
        higher; `tags` (name: value) set on every file. Returns the folder
        written (108 files for the tilted Philips series)."""
        import pydicom  # python3-pydicom, as the scripts that call this
        out = tempfile.mkdtemp(prefix='two-echoes-', dir=self.tmp)
        for name in sorted(os.listdir(folder)):
            try:
                first = pydicom.dcmread(os.path.join(folder, name))
            except pydicom.errors.InvalidDicomError:
                continue  # a README, a licence
            if 'PixelData' not in first:
                continue  # the scanner's DICOMDIR
            for echo in (1, 2):
                ds = pydicom.dcmread(os.path.join(folder, name))
                for key, value in (tags or {}).items():
                    setattr(ds, key, value)
                ds.SeriesInstanceUID = series_uid
                ds.SOPInstanceUID = f'{series_uid}.{echo}.{ds.InstanceNumber}'
                ds.file_meta.MediaStorageSOPInstanceUID = ds.SOPInstanceUID
                ds.file_meta.MediaStorageSOPClassUID = ds.SOPClassUID
                ds.EchoNumbers = echo
                if echo == 2:
                    pixels = ds.pixel_array
                    ds.PixelData = (pixels + offset).astype(pixels.dtype).tobytes()
                ds.save_as(os.path.join(out, f'{name}-{echo}.dcm'))
        return out

    def orthanc_upload_folder(self, folder, user, password):
        count = 0
        for name in sorted(os.listdir(folder)):
            path = os.path.join(folder, name)
            with open(path, 'rb') as f:
                data = f.read()
            if len(data) < 132 or data[128:132] != b'DICM':
                continue  # not DICOM (a README, a licence)
            if b'1.2.840.10008.1.3.10' in data[:1024]:
                continue  # a DICOMDIR (the scanner's DIRFILE): not an instance
            self.orthanc_request('POST', '/instances', user, password, data)
            count += 1
        return count

    def stop_orthanc(self):
        if self.orthanc.poll() is None:
            self.orthanc.send_signal(signal.SIGTERM)
            try:
                self.orthanc.wait(timeout=20)
            except subprocess.TimeoutExpired:
                self.orthanc.kill()
                self.orthanc.wait()

    # ---------------------------------------------------------------- end
    def close(self, keep=False):
        """Stops every process started; removes the temp folder unless
        `keep` (a failed test keeps its logs and screenshots there) or
        VPM_KEEP_TEST_FILES=1 (to look at what a passing test made)."""
        keep = keep or os.environ.get('VPM_KEEP_TEST_FILES') == '1'
        for p in reversed(self.procs):
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
                try:
                    p.wait(timeout=10)
                except subprocess.TimeoutExpired:
                    p.kill()
                    p.wait()
        if keep:
            print(f'      kept for inspection: {self.tmp}', flush=True)
        else:
            shutil.rmtree(self.tmp, ignore_errors=True)
