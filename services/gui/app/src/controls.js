// Touch controls for numbers: − and + buttons (48 px) beside a number field and a row of preset
// buttons under it. The field stays a field (typed into, filled by the browser tests); a button
// sets its value and fires 'input' and 'change' on it as typing would.

/// `value` + `delta` rounded to `digits` decimals and kept within [min, max]. An empty or
/// unreadable field counts from `base` (default: the minimum, else 0).
export function stepValue(value, delta, { min = -Infinity, max = Infinity, digits = 2, base } = {}) {
  const from = Number.isFinite(value) ? value : base !== undefined ? base : Number.isFinite(min) ? min : 0;
  const v = Math.min(max, Math.max(min, from + delta));
  return Number(v.toFixed(digits));
}

/// Sets `input` to `value` (shown with `digits` decimals) and fires its events.
function setInput(input, value, digits) {
  input.value = value.toFixed(digits);
  input.dispatchEvent(new Event('input', { bubbles: true }));
  input.dispatchEvent(new Event('change', { bubbles: true }));
}

/// Puts `input` (a number field) between − and + buttons that change it by `step`, within the
/// field's min and max (an empty field counts from `base`), and adds buttons for `presets`
/// ([value] or [[value, label]]) below. The preset equal to the field's value is marked active.
/// Returns the outermost element it made.
export function stepper(input, { step, digits = 2, presets = [], unit = '', name = '', base }) {
  const min = input.min !== '' ? parseFloat(input.min) : -Infinity;
  const max = input.max !== '' ? parseFloat(input.max) : Infinity;
  const what = name || input.getAttribute('aria-label') || input.id;
  const wrap = document.createElement('div');
  wrap.className = 'stepper';
  const button = (text, label, cls) => {
    const b = document.createElement('button');
    b.type = 'button';
    b.className = cls;
    b.textContent = text;
    b.setAttribute('aria-label', label);
    return b;
  };
  const minus = button('−', `${what} − ${step}${unit}`, 'step minus');
  const plus = button('+', `${what} + ${step}${unit}`, 'step plus');
  minus.onclick = () => setInput(input, stepValue(parseFloat(input.value), -step, { min, max, digits, base }), digits);
  plus.onclick = () => setInput(input, stepValue(parseFloat(input.value), step, { min, max, digits, base }), digits);
  input.replaceWith(wrap);
  wrap.append(minus, input, plus);
  if (!presets.length) return wrap;
  const row = document.createElement('div');
  row.className = 'presets';
  const buttons = presets.map((p) => {
    const [value, label] = Array.isArray(p) ? p : [p, `${p}${unit}`];
    const b = button(label, `${what} ${label}`, 'preset');
    b.dataset.value = value;
    b.onclick = () => setInput(input, value, digits);
    row.append(b);
    return b;
  });
  const mark = () => {
    const v = parseFloat(input.value);
    for (const b of buttons) b.classList.toggle('active', Math.abs(parseFloat(b.dataset.value) - v) < 1e-9);
  };
  input.addEventListener('input', mark);
  input.concertMarkPresets = mark;
  mark();
  wrap.after(row);
  const outer = document.createElement('div');
  outer.className = 'stepper-group';
  wrap.replaceWith(outer);
  outer.append(wrap, row);
  return outer;
}
/// Marks the active preset again after the field was set by code (no event).
export function syncPresets(input) { if (input.concertMarkPresets) input.concertMarkPresets(); }
