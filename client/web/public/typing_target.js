// Whether a keyboard event's target takes typed characters, so that a key
// pressed there is the field's own and not a page shortcut (view_keys.js,
// undo_keys.js). An ES module with no dependencies.

// Inputs that take no typed characters: a key pressed on them is the page's.
const kKeylessInputs = new Set(['checkbox', 'radio', 'range', 'button', 'submit', 'reset', 'file',
                                'color', 'image']);

// True when `target` (an element) takes typed characters: a text, number,
// date ... input, a text area, an editable element.
export function takesTyping(target) {
  if (!target || typeof target !== 'object') return false;
  if (target.isContentEditable) return true;
  const tag = String(target.tagName ?? '').toUpperCase();
  if (tag === 'TEXTAREA') return true;
  return tag === 'INPUT' && !kKeylessInputs.has(String(target.type ?? 'text').toLowerCase());
}
