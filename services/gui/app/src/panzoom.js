// Pan and zoom of an SVG map through its viewBox: a wheel or a pinch zooms about the point under
// the cursor or the fingers, a drag pans, a tap (a press and release that did not move) is handed
// to `onTap`. Only the viewBox changes, so getScreenCTM() keeps mapping the map's coordinates
// to the screen (the storey view's toScreen() for the browser test relies on it). The view
// arithmetic is pure (zoomView, panView: tested by app/test/storey_test.mjs).

/// The viewBox {x, y, w, h} scaled by `f` (> 1: zoomed out) about the point (px, py) of the
/// map, which stays where it is on the screen (with preserveAspectRatio's uniform scale and
/// centring, scaling w and h together keeps the letterbox offsets).
export function zoomView(v, px, py, f) {
  return { x: px - (px - v.x) * f, y: py - (py - v.y) * f, w: v.w * f, h: v.h * f };
}
/// The viewBox moved so that the map follows a drag of (dx, dy) in map units.
export function panView(v, dx, dy) {
  return { x: v.x - dx, y: v.y - dy, w: v.w, h: v.h };
}
/// The zoom factor `f` limited so that the view's width stays within [minW, maxW].
export function clampZoom(v, f, minW, maxW) {
  return Math.min(Math.max(f, minW / v.w), maxW / v.w);
}

/// A press that moves less than this [px] is a tap (a finger wobbles).
const TAP_SLOP = 8;

export class PanZoom {
  /// `svg`: the map; `fit()`: the viewBox showing everything (recomputed by the caller);
  /// `onTap(clientX, clientY)`; `onChange()`: after every view change (to redraw what depends on
  /// the scale).
  constructor(svg, { fit, onTap, onChange = () => {}, minWidth = 0.5, maxZoomOut = 4 }) {
    Object.assign(this, { svg, fit, onTap, onChange, minWidth, maxZoomOut });
    this.user = null;            // the viewBox after a pan or zoom; null: fit
    this.pointers = new Map();   // pointerId -> {x, y} (client px)
    this.moved = false;          // the current press became a pan or pinch
    this.start = null;           // where the first pointer went down
    svg.addEventListener('pointerdown', (e) => this.down(e));
    svg.addEventListener('pointermove', (e) => this.move(e));
    svg.addEventListener('pointerup', (e) => this.up(e, true));
    svg.addEventListener('pointercancel', (e) => this.up(e, false));
    svg.addEventListener('lostpointercapture', (e) => this.pointers.delete(e.pointerId));
    svg.addEventListener('wheel', (e) => this.wheel(e), { passive: false });
  }
  view() { return this.user || this.fit(); }
  zoomed() { return this.user !== null; }
  apply() {
    const v = this.view();
    this.svg.setAttribute('viewBox', `${v.x} ${v.y} ${v.w} ${v.h}`);
  }
  set(v) { this.user = v; this.apply(); this.onChange(); }
  reset() { this.set(null); }
  /// Zooms by `f` about the client point (cx, cy), by default the map's centre.
  zoomBy(f, cx, cy) {
    const v = this.view();
    const p = cx === undefined ? { x: v.x + v.w / 2, y: v.y + v.h / 2 } : this.toMap(cx, cy);
    if (!p) return;
    const fit = this.fit();
    f = clampZoom(v, f, this.minWidth, fit.w * this.maxZoomOut);
    this.set(zoomView(v, p.x, p.y, f));
  }
  /// The map point under the client point, or null when the map is not on screen.
  toMap(cx, cy) {
    const m = this.svg.getScreenCTM();
    if (!m || !m.a) return null;
    const p = new DOMPoint(cx, cy).matrixTransform(m.inverse());
    return { x: p.x, y: p.y };
  }
  /// Screen pixels per map unit.
  scale() {
    const m = this.svg.getScreenCTM();
    return m && m.a ? m.a : 0;
  }
  down(e) {
    if (e.pointerType === 'mouse' && e.button !== 0) return;
    if (!this.pointers.size) { this.moved = false; this.start = { x: e.clientX, y: e.clientY }; }
    this.pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
    if (this.pointers.size > 1) this.moved = true;  // a pinch is never a tap
    try { this.svg.setPointerCapture(e.pointerId); } catch (err) { /* a synthetic pointer */ }
  }
  move(e) {
    const last = this.pointers.get(e.pointerId);
    if (!last) return;
    const k = this.scale();
    if (!k) return;
    if (this.pointers.size === 1) {
      if (!this.moved && Math.hypot(e.clientX - this.start.x, e.clientY - this.start.y) < TAP_SLOP) return;
      this.moved = true;
      this.pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
      this.set(panView(this.view(), (e.clientX - last.x) / k, (e.clientY - last.y) / k));
      return;
    }
    // Two fingers (the first two): zoom by the change of their distance about their midpoint,
    // and pan by the midpoint's move.
    const [a, b] = [...this.pointers.values()];
    const before = { mx: (a.x + b.x) / 2, my: (a.y + b.y) / 2, d: Math.hypot(a.x - b.x, a.y - b.y) };
    this.pointers.set(e.pointerId, { x: e.clientX, y: e.clientY });
    const [c, d] = [...this.pointers.values()];
    const after = { mx: (c.x + d.x) / 2, my: (c.y + d.y) / 2, d: Math.hypot(c.x - d.x, c.y - d.y) };
    if (before.d < 1 || after.d < 1) return;
    let v = panView(this.view(), (after.mx - before.mx) / k, (after.my - before.my) / k);
    const p = this.toMap(after.mx, after.my);
    if (p) {
      // toMap() still sees the view before the pan: shift the point by the pan.
      const px = p.x - (after.mx - before.mx) / k, py = p.y - (after.my - before.my) / k;
      const f = clampZoom(v, before.d / after.d, this.minWidth, this.fit().w * this.maxZoomOut);
      v = zoomView(v, px, py, f);
    }
    this.set(v);
  }
  up(e, released) {
    if (!this.pointers.has(e.pointerId)) return;
    this.pointers.delete(e.pointerId);
    if (released && !this.moved && !this.pointers.size) this.onTap(e.clientX, e.clientY);
  }
  wheel(e) {
    e.preventDefault();
    const lines = e.deltaMode === 1 ? 16 : e.deltaMode === 2 ? 400 : 1;
    this.zoomBy(Math.exp(Math.max(-300, Math.min(300, e.deltaY * lines)) * 0.002), e.clientX, e.clientY);
  }
}
