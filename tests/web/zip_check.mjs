// Reads a ZIP archive back with Python's zipfile (python3 is one of the
// project's dependencies), for the tests of the page's ZIP writer: every
// member's CRC is tested first (ZipFile.testzip), then each member's name,
// size, compression method, CRC and bytes are returned.
import { execFileSync } from 'node:child_process';

const kScript = `
import base64, json, sys, zipfile
with zipfile.ZipFile(sys.argv[1]) as z:
    bad = z.testzip()
    if bad is not None:
        sys.exit('bad CRC: ' + bad)
    print(json.dumps([dict(name=i.filename, size=i.file_size, method=i.compress_type, crc=i.CRC,
                           utf8=bool(i.flag_bits & 0x800),
                           data=base64.b64encode(z.read(i)).decode()) for i in z.infolist()]))
`;

// [{name, size, method, crc, utf8, bytes}] of the archive at `file`; throws
// when Python cannot read it or a CRC does not match.
export function readZip(file) {
  const members = JSON.parse(execFileSync('python3', ['-c', kScript, file],
                                          { maxBuffer: 1 << 30 }).toString());
  return members.map(({ data, ...m }) => ({ ...m, bytes: Buffer.from(data, 'base64') }));
}
