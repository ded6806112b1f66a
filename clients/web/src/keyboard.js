// Keyboard shortcuts and the help dialog that lists them (`?`). The table below is the one source
// of both: the dialog is built from it. Shortcuts act only when the focus is not in a text field.

/** [keys, what, action name or null (handled elsewhere: listed for help only)] */
export const SHORTCUTS = [
  ['?', 'Show this help', 'help'],
  ['Esc', 'Close this help or the export menu', null],
  ['r', 'Reset the view', 'resetView'],
  ['h', 'Hide or show the panel', 'togglePanel'],
  ['n', 'Add a surface', 'addSurface'],
  ['w', 'Wireframe on or off', 'toggleWireframe'],
  ['a', 'Axes on or off', 'toggleAxes'],
  ['g', 'Grid on or off', 'toggleGrid'],
  ['c', 'Next colouring: surface colour, height, normal', 'nextColorMode'],
  ['p', 'Pause or resume refinement', 'togglePause'],
  ['Enter', 'In an equation: draw it', null],
  ['← → or ↓ ↑', 'On a slider: one step (Page Up / Page Down: ten, Home / End: min / max)', null],
  ['drag · wheel · right drag', 'Orbit · zoom · pan the view', null],
];

/** True when a key pressed in `target` is typing, not a shortcut. */
export function isTyping(target) {
  if (!target || !target.tagName) return false;
  if (target.isContentEditable || target.tagName === 'TEXTAREA' || target.tagName === 'SELECT') return true;
  if (target.tagName !== 'INPUT') return false;
  return !['range', 'checkbox', 'button', 'color', 'radio'].includes(target.type);
}

/**
 * Fills the help dialog's table and binds the shortcuts: `actions` maps the action names above to
 * functions.
 */
export function bindShortcuts(dialog, table, actions) {
  for (const [keys, what] of SHORTCUTS) {
    const tr = table.insertRow();
    const kbd = document.createElement('kbd');
    kbd.textContent = keys;
    tr.insertCell().append(kbd);
    tr.insertCell().textContent = what;
  }
  actions.help ??= () => (dialog.open ? dialog.close() : dialog.showModal());
  document.addEventListener('keydown', (event) => {
    if (event.ctrlKey || event.metaKey || event.altKey || isTyping(event.target)) return;
    const entry = SHORTCUTS.find(([keys, , action]) => action && keys === event.key);
    if (!entry || (dialog.open && entry[2] !== 'help')) return;
    event.preventDefault();
    actions[entry[2]]?.();
  });
}
