#!/usr/bin/env python3
"""A small misbehaving DICOMweb server, for the PACS fault tests.

Serves QIDO-RS and WADO-RS from DICOM files in folders, under a path
prefix that picks the behaviour (http://127.0.0.1:PORT/MODE/studies...):

  good       offset honoured, quoted boundary, per-part Content-Length;
             requires "Authorization: Bearer good-token"
  quirky     offset ignored (the first page again), unquoted boundary, no
             per-part Content-Length, a preamble, extra part headers
  truncated  the WADO-RS body stops in the middle of a part
  s401 s403 s404 s500   every request answered with that status
  w401 w403 w404 w500   searches and listings answered, the retrieval with that status
  sr         the series' instances are a structured report (no pixels)
  mixed      the series' instances and one of another series
  notdicom   a part that is not a DICOM file
  stall      one part, then nothing for a long time
  slow       like good (without auth), one part every 25 ms

Usage: fake_dicomweb.py CT_FOLDER SR_FOLDER OTHER_FOLDER PORT_FILE
(listens on a free loopback port and writes it to PORT_FILE). Counts the
requests per mode at GET /_counts.
"""
import json
import os
import sys
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from urllib.parse import parse_qs, urlparse

import pydicom

STUDIES = 5
counts = {}


def load(folder):
    out = []
    for name in sorted(os.listdir(folder)):
        with open(os.path.join(folder, name), 'rb') as f:
            out.append(f.read())
    return out


def study_json(i, uid):
    return {'0020000D': {'vr': 'UI', 'Value': [uid]},
            '00100010': {'vr': 'PN', 'Value': [{'Alphabetic': f'FAKE^PATIENT{i}'}]},
            '00100020': {'vr': 'LO', 'Value': [f'FAKE{i}']},
            '00080061': {'vr': 'CS', 'Value': ['CT']},
            '00201206': {'vr': 'IS', 'Value': [2]}}


class Handler(BaseHTTPRequestHandler):
    protocol_version = 'HTTP/1.1'

    def log_message(self, *args):
        pass

    def send(self, status, body=b'', content_type='application/dicom+json', close=False):
        self.send_response(status)
        self.send_header('Content-Type', content_type)
        self.send_header('Content-Length', str(len(body)))
        if close:
            self.send_header('Connection', 'close')
        self.end_headers()
        self.wfile.write(body)

    def do_GET(self):
        url = urlparse(self.path)
        parts = url.path.strip('/').split('/')
        if parts == ['_counts']:
            return self.send(200, json.dumps(counts).encode(), 'application/json')
        mode, rest = parts[0], parts[1:]
        counts[mode] = counts.get(mode, 0) + 1
        if mode.startswith('s') and mode[1:].isdigit():
            return self.send(int(mode[1:]), b'{"error": "as configured"}', 'application/json')
        if mode[0] == 'w' and mode[1:].isdigit() and len(rest) == 4:
            return self.send(int(mode[1:]), b'{"error": "as configured"}', 'application/json')
        if mode == 'good' and self.headers.get('Authorization') != 'Bearer good-token':
            return self.send(401, b'', 'text/plain')
        query = parse_qs(url.query)
        server = self.server
        if rest == ['studies']:
            limit = int(query.get('limit', ['100'])[0])
            offset = 0 if mode == 'quirky' else int(query.get('offset', ['0'])[0])
            uids = [server.study] + [f'{server.study}.{i}' for i in range(1, STUDIES)]
            page = [study_json(i, u) for i, u in enumerate(uids)][offset:offset + limit]
            return self.send(200, json.dumps(page).encode())
        if len(rest) == 3 and rest[0] == 'studies' and rest[2] == 'series':
            series = [{'0020000E': {'vr': 'UI', 'Value': [server.series]},
                       '00080060': {'vr': 'CS', 'Value': ['SR' if mode == 'sr' else 'CT']},
                       '00201209': {'vr': 'IS', 'Value': [len(server.ct)]}}]
            return self.send(200, json.dumps(series).encode())
        if len(rest) == 4 and rest[0] == 'studies' and rest[2] == 'series':
            return self.wado(mode)
        return self.send(404, b'', 'text/plain')

    def wado(self, mode):
        s = self.server
        files = {'sr': s.sr, 'mixed': s.ct + s.other[:1], 'notdicom': [b'hello, not DICOM'],
                 'stall': s.ct[:1]}.get(mode, s.ct)
        boundary = 'vpm-fake-' + mode
        quoted = mode != 'quirky'
        body = b'preamble to skip\r\n' if mode == 'quirky' else b''
        for data in files:
            body += f'--{boundary}\r\nContent-Type: application/dicom\r\n'.encode()
            if mode == 'quirky':
                body += b'X-Extra: yes\r\n'
            else:
                body += f'Content-Length: {len(data)}\r\n'.encode()
            body += b'\r\n' + data + b'\r\n'
        body += f'--{boundary}--\r\n'.encode()
        if mode == 'truncated':
            body = body[:len(body) // 2]
        ctype = ('multipart/related; type="application/dicom"; boundary='
                 + (f'"{boundary}"' if quoted else boundary))
        self.send_response(200)
        self.send_header('Content-Type', ctype)
        # No overall length: the body ends when the connection closes, so a
        # cut body is seen by the parser, not by the transport.
        self.send_header('Connection', 'close')
        self.end_headers()
        if mode == 'slow':
            marker = f'--{boundary}'.encode()
            at = 0
            while at < len(body):
                following = body.find(marker, at + 1)
                end = len(body) if following < 0 else following
                self.wfile.write(body[at:end])
                self.wfile.flush()
                time.sleep(0.025)
                at = end
            self.close_connection = True
            return
        if mode == 'stall':
            self.wfile.write(body[:len(body) - 10])
            self.wfile.flush()
            time.sleep(60)
            return
        self.wfile.write(body)
        self.close_connection = True


def main():
    ct, sr, other, port_file = sys.argv[1:5]
    server = ThreadingHTTPServer(('127.0.0.1', 0), Handler)
    server.daemon_threads = True
    server.ct, server.sr, server.other = load(ct), load(sr), load(other)
    first = pydicom.dcmread(os.path.join(ct, sorted(os.listdir(ct))[0]), stop_before_pixels=True)
    server.study, server.series = first.StudyInstanceUID, first.SeriesInstanceUID
    with open(port_file + '.tmp', 'w') as f:
        f.write(str(server.server_address[1]))
    os.rename(port_file + '.tmp', port_file)
    server.serve_forever()


if __name__ == '__main__':
    main()
