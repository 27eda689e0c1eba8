// The page's side of an upload from the desktop: the ZIP it packs DICOM
// files into (public/zip_writer.js), read back by Python's zipfile (CRCs
// tested, names and bytes as packed, zip_check.mjs), and what it
// sends for what the user picked (public/upload_files.js): one volume file
// or archive as is, a folder or several files as FOLDER.zip with plain,
// distinct member names (no folders, no '..', hidden files left out), the
// gateway's cap applied before any work, and the file names the server
// takes.
// Usage: node --test upload_files.test.mjs
import assert from 'node:assert/strict';
import { execFileSync } from 'node:child_process';
import crypto from 'node:crypto';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import test from 'node:test';
import { fileURLToPath, pathToFileURL } from 'node:url';

import { readZip } from './zip_check.mjs';

const here = path.dirname(fileURLToPath(import.meta.url));
const load = (file) => import(pathToFileURL(path.join(here, '../../client/web/public', file)).href);
const { crc32, storeZip, storedZipBytes, kMaxZipEntries } = await load('zip_writer.js');
const { planUpload, sizeText, uploadExtension, uploadFileName, zipEntries, zipName } =
  await load('upload_files.js');

const item = (p, content = p) => ({ file: new File([content], p.split('/').at(-1)), path: p });

// The archive on disk, for python3.
async function written(blob) {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'vpm-zip-test-'));
  const file = path.join(dir, 'a.zip');
  fs.writeFileSync(file, Buffer.from(await blob.arrayBuffer()));
  return { file, done: () => fs.rmSync(dir, { recursive: true, force: true }) };
}

test('Crc32_MatchesTheStandardCheckValues', () => {
  const ascii = (s) => new TextEncoder().encode(s);
  assert.equal(crc32(ascii('123456789')), 0xcbf43926);
  assert.equal(crc32(new Uint8Array(0)), 0);
  assert.equal(crc32(ascii('The quick brown fox jumps over the lazy dog')), 0x414fa339);
  // Continued over two pieces as over one.
  assert.equal(crc32(ascii('56789'), crc32(ascii('1234'))), 0xcbf43926);
  const random = crypto.randomBytes(100000);
  assert.equal(crc32(random), Number.parseInt(
    execFileSync('python3', ['-c', 'import sys, zlib; print(zlib.crc32(sys.stdin.buffer.read()))'],
                 { input: random }).toString().trim(), 10));
});

test('StoreZip_IsReadByPythonWithEveryByteAndCrc', async () => {
  const big = crypto.randomBytes(5 * 1024 * 1024 + 17);  // more than one CRC slice
  const entries = [
    { name: 'IM0001', blob: new File([crypto.randomBytes(1000)], 'IM0001') },
    { name: 'empty', blob: new File([], 'empty') },
    { name: 'Ünïcödé ñame.dcm', blob: new File(['résumé'], 'x') },
    { name: 'big', blob: new File([big], 'big') },
  ];
  const seen = [];
  const zip = await storeZip(entries, { onProgress: (done, total) => seen.push([done, total]) });
  assert.equal(zip.size, storedZipBytes(entries));
  const total = entries.reduce((s, e) => s + e.blob.size, 0);
  assert.deepEqual(seen.at(-1), [total, total]);
  const { file, done } = await written(zip);
  try {
    const members = readZip(file);
    assert.deepEqual(members.map((m) => [m.name, m.size, m.method, m.utf8]),
                     entries.map((e) => [e.name, e.blob.size, 0, true]));
    for (const [i, e] of entries.entries()) {
      assert.ok(members[i].bytes.equals(Buffer.from(await e.blob.arrayBuffer())), e.name);
      assert.equal(members[i].crc, crc32(new Uint8Array(await e.blob.arrayBuffer())), e.name);
    }
  } finally {
    done();
  }
  // The same files make the same archive.
  const again = await storeZip(entries);
  assert.ok(Buffer.from(await again.arrayBuffer()).equals(Buffer.from(await zip.arrayBuffer())));
});

test('StoreZip_StopsWhenAborted', async () => {
  const controller = new AbortController();
  controller.abort(new Error('cancelled'));
  await assert.rejects(storeZip([{ name: 'a', blob: new File(['x'], 'a') }],
                                { signal: controller.signal }), /cancelled/);
});

test('UploadFileName_TakesWhatTheServerReadsInLowerCase', () => {
  assert.equal(uploadFileName('case.nii'), 'case.nii');
  assert.equal(uploadFileName('SCAN.NII.GZ'), 'SCAN.nii.gz');
  assert.equal(uploadFileName('a.b.Nrrd'), 'a.b.nrrd');
  assert.equal(uploadFileName('head.mha'), 'head.mha');
  assert.equal(uploadFileName('Series 3.ZIP'), 'Series 3.zip');
  assert.equal(uploadFileName('ct.tgz'), 'ct.tgz');
  assert.equal(uploadExtension('x.nii.gz'), '.nii.gz');
  assert.equal(uploadExtension('x.gz'), null);
  assert.equal(uploadExtension('.nii'), null);
  for (const bad of ['', 'a/b.nii', 'a\\b.nii', '.hidden.nii', 'x.txt', 'x.dcm', 'nii', 'a\nb.nii',
                     `${'é'.repeat(127)}.nii`]) {
    assert.throws(() => uploadFileName(bad), Error, JSON.stringify(bad));
  }
  // The reason never quotes the name (the gateway logs reasons).
  assert.throws(() => uploadFileName('DOE^JOHN.txt'), (e) => !e.message.includes('DOE'));
});

test('ZipEntries_PlainDistinctNamesWithoutFolders', () => {
  const entries = zipEntries([item('CT/SE1/IM1'), item('CT/SE2/IM1'), item('CT/SE2/im1'),
                              item('CT/../../etc/passwd'), item('CT/a:b*c'), item('CT/..')]);
  const names = entries.map((e) => e.name);
  assert.equal(new Set(names.map((n) => n.toLowerCase())).size, names.length);
  for (const n of names) {
    assert.ok(!/[/\\]/.test(n) && !n.startsWith('.') && n !== '', n);
  }
  assert.deepEqual(names, ['file', 'passwd', 'IM1', 'IM1_2', 'im1_3', 'a_b_c']);  // in path order
  assert.equal(zipName([item('SMITH^ANNA/SE1/IM1'), item('SMITH^ANNA/IM2')]), 'SMITH^ANNA.zip');
  assert.equal(zipName([item('IM0001.dcm'), item('IM0002.dcm')]), 'IM0001.zip');
  assert.equal(zipName([item('a/IM1'), item('b/IM2')]), 'IM1.zip');
  assert.equal(zipName([item('...')]), 'dicom.zip');
});

test('PlanUpload_OneFileAsIsSeveralAsAZipHiddenLeftOut', () => {
  const one = planUpload([item('Case.NII.GZ', 'abc')], 1000);
  assert.deepEqual([one.kind, one.name, one.bytes], ['file', 'Case.nii.gz', 3]);
  assert.equal(planUpload([item('dicom.zip')], 1000).kind, 'file');
  const folder = planUpload([item('CT/IM1'), item('CT/IM2'), item('CT/.DS_Store'),
                             item('CT/.git/config'), item('__MACOSX/CT/._IM1')], 10000);
  assert.equal(folder.kind, 'zip');
  assert.equal(folder.name, 'CT.zip');
  assert.deepEqual(folder.entries.map((e) => e.name), ['IM1', 'IM2']);
  assert.equal(folder.bytes, storedZipBytes(folder.entries));
  // A single DICOM file is packed too.
  assert.equal(planUpload([item('IM1.dcm')], 1000).kind, 'zip');
  assert.throws(() => planUpload([item('.hidden'), item('x/.y')], 1000), /Nothing to upload/);
  assert.throws(() => planUpload([item('a.nii'), item('IM1')], 1000), /came with other files/);
  assert.throws(() => planUpload([item('a.nii', '')], 1000), /is empty/);
  assert.throws(() => planUpload([item('a.nii', 'x'.repeat(1001))], 1000),
                /a\.nii is 1001 bytes; this gateway takes uploads of at most 1000 bytes/);
  assert.throws(() => planUpload([item('CT/IM1', 'x'.repeat(900)), item('CT/IM2')], 1000),
                /CT\.zip \(2 files\) is .* at most 1000 bytes/);
  const many = Array.from({ length: kMaxZipEntries + 1 }, (_, i) => item(`CT/${i}`, ''));
  assert.throws(() => planUpload(many, 0), /at most 65535/);
  assert.equal(sizeText(1288490188), '1.2 GiB');
  assert.equal(sizeText(512), '512 bytes');
});
