// What an upload from the desktop sends, decided from what the user picked
// or dropped (the page, upload_panel.js) and checked again by the gateway
// (lib/volume_upload.js), so both apply one rule:
//   - one NIfTI (.nii, .nii.gz), NRRD (.nrrd) or MetaImage (.mha) file, or
//     one archive of a DICOM series (.zip, .tar, .tar.gz, .tgz): sent as is;
//   - anything else (a DICOM folder, several DICOM files): packed into a
//     stored ZIP (zip_writer.js) named after the folder, FOLDER.zip, which
//     vpm-server reads as a DICOM folder (its largest CT or MR series).
// Hidden files and folders (a name starting with '.', and __MACOSX) are left
// out; archive members get plain names (the last part of their path, made
// unique), never a folder or '..'. Extensions are matched in any case and
// sent in lower case, as the server matches them.
// No DOM here: Node's tests load it too.
import { kMaxZipEntries, storedZipBytes } from './zip_writer.js';

// Longest first: '.nii.gz' before '.nii'.
const kSingleFileExtensions = ['.nii.gz', '.nii', '.nrrd', '.mha'];
const kArchiveExtensions = ['.tar.gz', '.tgz', '.tar', '.zip'];
export const kMaxFileNameBytes = 255;  // the server's file name limit
const kMaxStemChars = 120;             // a folder's name as the archive's

// The extension the server reads `name` by, in lower case, or null.
export function uploadExtension(name) {
  const lower = String(name).toLowerCase();
  return [...kSingleFileExtensions, ...kArchiveExtensions]
    .find((ext) => lower.endsWith(ext) && lower.length > ext.length) ?? null;
}

// `name` as sent to the server: a plain file name (no folder, no control
// character, not hidden), at most 255 UTF-8 bytes, with an extension the
// server reads, written in lower case. Throws an Error saying what is wrong
// (without quoting the name: the gateway logs nothing of it).
export function uploadFileName(name) {
  if (typeof name !== 'string' || name === '') throw new Error('the file has no name');
  // eslint-disable-next-line no-control-regex
  if (/[/\\\u0000-\u001f\u007f]/.test(name)) {
    throw new Error('the file name holds a folder or a control character');
  }
  if (name.startsWith('.')) throw new Error('the file name starts with a dot (a hidden file)');
  const ext = uploadExtension(name);
  if (!ext) {
    throw new Error('the file must end in .nii, .nii.gz, .nrrd or .mha, or be a .zip, .tar, ' +
                    '.tar.gz or .tgz of DICOM files');
  }
  const out = name.slice(0, name.length - ext.length) + ext;
  if (new TextEncoder().encode(out).length > kMaxFileNameBytes) {
    throw new Error(`the file name is over ${kMaxFileNameBytes} bytes`);
  }
  return out;
}

// A name part made safe for an archive's member or its own name: no
// separators, control or reserved characters, no leading dots.
function plainPart(text) {
  // eslint-disable-next-line no-control-regex
  return String(text).replace(/[/\\:*?"<>|\u0000-\u001f\u007f]/g, '_').replace(/^[.\s]+/, '')
    .trim().slice(0, kMaxStemChars);
}

const partsOf = (path) => String(path).split(/[/\\]/).filter((p) => p !== '');
const hidden = (path) => partsOf(path).some((p) => p.startsWith('.') || p === '__MACOSX');

// items: [{file, path}] (path: the file's path in what was picked, e.g.
// webkitRelativePath 'CT/IM0001', or its name). Returns those to pack, as
// [{name, blob}] with plain, distinct names, in path order.
export function zipEntries(items) {
  const used = new Set();
  const sorted = [...items].sort((a, b) => (a.path < b.path ? -1 : a.path > b.path ? 1 : 0));
  return sorted.map(({ file, path }) => {
    const base = plainPart(partsOf(path).at(-1) ?? '') || 'file';
    let name = base;
    for (let n = 2; used.has(name.toLowerCase()); ++n) name = `${base}_${n}`;
    used.add(name.toLowerCase());
    return { name, blob: file };
  });
}

// The archive's name: the folder all items share, else the first file's
// name without its extension; 'dicom' when nothing usable is left.
export function zipName(items) {
  const tops = new Set(items.map(({ path }) => (partsOf(path).length > 1 ? partsOf(path)[0] : '')));
  const [top] = tops;
  const stem = tops.size === 1 && top ? top : (partsOf(items[0]?.path ?? '').at(-1) ?? '')
    .replace(/\.[^.]*$/, '');
  return `${plainPart(stem) || 'dicom'}.zip`;
}

const kUnits = [['GiB', 2 ** 30], ['MiB', 2 ** 20], ['KiB', 2 ** 10]];
// 1288490188 -> '1.2 GiB'.
export function sizeText(bytes) {
  for (const [unit, size] of kUnits) {
    if (bytes >= size) return `${(bytes / size).toFixed(bytes >= 10 * size ? 0 : 1)} ${unit}`;
  }
  return `${bytes} bytes`;
}

// What to send for items [{file, path}] under a cap of maxBytes:
//   {kind: 'file', name, blob, bytes}      one volume file or archive, as is
//   {kind: 'zip', name, entries, bytes}    DICOM files to pack (entries for storeZip)
// Throws an Error whose message the page shows when there is nothing to
// send, a volume file comes with other files, or the upload would pass
// the cap.
export function planUpload(items, maxBytes) {
  const shown = items.filter(({ path }) => !hidden(path));
  if (!shown.length) {
    throw new Error('Nothing to upload: pick a NIfTI, NRRD or MetaImage file, a .zip of DICOM ' +
                    'files, or a DICOM folder (hidden files are left out).');
  }
  const cap = (bytes, what) => {
    if (maxBytes > 0 && bytes > maxBytes) {
      throw new Error(`${what} is ${sizeText(bytes)}; this gateway takes uploads of at most ` +
                      `${sizeText(maxBytes)}.`);
    }
  };
  if (shown.length === 1 && uploadExtension(shown[0].file.name)) {
    const { file } = shown[0];
    const name = uploadFileName(file.name);
    if (file.size === 0) throw new Error(`${file.name} is empty.`);
    cap(file.size, file.name);
    return { kind: 'file', name, blob: file, bytes: file.size };
  }
  const odd = shown.find(({ file }) => uploadExtension(file.name));
  if (odd) {
    throw new Error(`${odd.file.name} came with other files: upload one NIfTI, NRRD or MetaImage ` +
                    'file, or one archive, alone; several files are taken as DICOM files.');
  }
  if (shown.length > kMaxZipEntries) {
    throw new Error(`${shown.length} files; at most ${kMaxZipEntries} go into one upload.`);
  }
  const entries = zipEntries(shown);
  const name = zipName(shown);
  const bytes = storedZipBytes(entries);
  cap(bytes, `${name} (${shown.length} files)`);
  return { kind: 'zip', name, entries, bytes };
}
