// The Stack picker: where the series shown holds several stacks (planes, or
// echoes, phases, b-values at the same positions: VolumeInfo.stacks), a
// select names them and opens another; hidden for every other volume.
import { parsePacsSource } from './pacs_source.js';

// source with its stack set to n (1-based): pacs:.../SERIES_UID?stack=N for
// a PACS series, FOLDER?...&stack=N for a folder of the data root (the
// folder's other keys, series= and spacing=, kept).
export function sourceWithStack(source, n) {
  const pacs = parsePacsSource(source);
  if (pacs) return `pacs:${pacs.endpoint}/${pacs.studyUid}/${pacs.seriesUid}?stack=${n}`;
  const question = source.lastIndexOf('?');
  const path = question < 0 ? source : source.slice(0, question);
  const keys = question < 0 ? [] : source.slice(question + 1).split('&')
    .filter((kv) => kv && !kv.startsWith('stack='));
  return `${path}?${[...keys, `stack=${n}`].join('&')}`;
}

export class StackPicker {
  // label: the <label> around select (hidden when there is no choice);
  // open(source, text): opens another stack's source; text names it.
  constructor({ label, select, open }) {
    Object.assign(this, { label, select, open, source: null });
    select.addEventListener('change', () => {
      const n = Number(select.value);
      if (!this.source || !(n >= 1)) return;
      this.open(sourceWithStack(this.source, n), select.selectedOptions[0]?.textContent ?? '');
    });
  }

  // volume: the VolumeInfo just opened.
  show(volume) {
    const stacks = volume?.stacks ?? [];
    const shown = stacks.length > 1 && volume.stack >= 1 && typeof volume.source === 'string' &&
      !volume.source.startsWith('upload:');
    this.label.hidden = !shown;
    this.source = shown ? volume.source : null;
    if (!shown) return;
    this.select.replaceChildren(...stacks.map((text, i) => {
      const option = document.createElement('option');
      option.value = String(i + 1);
      option.textContent = `${i + 1}: ${text}`;
      return option;
    }));
    this.select.value = String(volume.stack);
  }
}
