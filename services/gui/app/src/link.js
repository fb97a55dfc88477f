// The WebSocket link to the gateway (services/gui/include/gui/protocol.hpp): reconnects,
// re-subscribes, and answers publish() with the gateway's ack or error.
export class Link {
  constructor(url) {
    this.url = url;
    this.handlers = new Map();   // topic -> Set(fn(data, instance))
    this.rates = new Set();
    this.frames = new Map();     // topic -> fn(header, blob)
    this.pending = new Map();    // id -> {resolve, reject}
    this.subs = new Map();       // topic -> max_hz
    this.nextId = 1;
    this.hello = null;
    this.onstate = () => {};
    this.onhello = () => {};
    this.connect();
  }
  connect() {
    const ws = new WebSocket(this.url);
    ws.binaryType = 'arraybuffer';
    this.ws = ws;
    ws.onopen = () => {
      this.onstate(true);
      for (const [topic, hz] of this.subs) this.send({ op: 'subscribe', topic, max_hz: hz });
    };
    ws.onclose = () => {
      this.onstate(false);
      for (const p of this.pending.values()) p.reject(new Error('connection lost'));
      this.pending.clear();
      setTimeout(() => this.connect(), 1000);
    };
    ws.onmessage = (ev) => this.receive(ev.data);
  }
  send(m) { if (this.ws.readyState === 1) this.ws.send(JSON.stringify(m)); }
  receive(raw) {
    if (raw instanceof ArrayBuffer) {
      const bytes = new Uint8Array(raw);
      const nl = bytes.indexOf(10);
      const header = JSON.parse(new TextDecoder().decode(bytes.subarray(0, nl)));
      const fn = this.frames.get(header.topic);
      if (fn) fn(header, new Blob([bytes.subarray(nl + 1)], { type: 'image/jpeg' }));
      return;
    }
    const m = JSON.parse(raw);
    if (m.op === 'hello') { this.hello = m; this.onhello(m); return; }
    if (m.op === 'sample') {
      for (const fn of this.handlers.get(m.topic) || []) fn(m.data, m.instance);
      return;
    }
    if (m.op === 'rates') { for (const fn of this.rates) fn(m.topics); return; }
    if ((m.op === 'ack' || m.op === 'error') && m.id !== undefined && this.pending.has(m.id)) {
      const p = this.pending.get(m.id);
      this.pending.delete(m.id);
      if (m.op === 'ack') p.resolve(m); else p.reject(new Error(m.error));
    }
  }
  subscribe(topic, fn, maxHz = 0) {
    if (!this.handlers.has(topic)) this.handlers.set(topic, new Set());
    this.handlers.get(topic).add(fn);
    if (!this.subs.has(topic)) {
      this.subs.set(topic, maxHz);
      this.send({ op: 'subscribe', topic, max_hz: maxHz });
    }
  }
  watchFrames(topic, fn, maxHz = 2) {
    if (this.frames.size) for (const t of this.frames.keys()) this.unwatchFrames(t);
    this.frames.set(topic, fn);
    this.subs.set(topic, maxHz);
    this.send({ op: 'subscribe', topic, max_hz: maxHz });
  }
  unwatchFrames(topic) {
    this.frames.delete(topic);
    this.subs.delete(topic);
    this.send({ op: 'unsubscribe', topic });
  }
  publish(topic, data) {
    const id = this.nextId++;
    return new Promise((resolve, reject) => {
      if (this.ws.readyState !== 1) { reject(new Error('not connected to the gateway')); return; }
      this.pending.set(id, { resolve, reject });
      this.ws.send(JSON.stringify({ op: 'publish', topic, data, id }));
    });
  }
  hasTopic(topic) { return !!this.hello && this.hello.topics.some((t) => t.topic === topic); }
  topicsMatching(re) { return this.hello ? this.hello.topics.filter((t) => re.test(t.topic)) : []; }
}
