// Undo and redo from the keyboard: Ctrl+Z undoes, Ctrl+Shift+Z (and Ctrl+Y)
// redoes; Cmd in place of Ctrl on macOS. Keys typed into a text field stay
// the field's own (its text's undo): typing_target.js.

import { takesTyping } from './typing_target.js';

// e: a KeyboardEvent (or a plain object with its fields). Returns 'undo',
// 'redo' or null.
export function undoKey(e) {
  if (!(e.ctrlKey || e.metaKey) || e.altKey) return null;
  const key = String(e.key ?? '').toLowerCase();
  const code = e.code ?? '';
  if (key === 'z' || code === 'KeyZ') return e.shiftKey ? 'redo' : 'undo';
  if ((key === 'y' || code === 'KeyY') && !e.shiftKey && !e.metaKey) return 'redo';
  return null;
}

// Calls onKey('undo' | 'redo') for those keys pressed anywhere on `target`
// (the document) but in a text field.
export function installUndoKeys(target, onKey) {
  target.addEventListener('keydown', (e) => {
    const action = undoKey(e);
    if (!action || takesTyping(e.target) || e.repeat) return;
    e.preventDefault();
    onKey(action);
  });
}
