// The WebSocket link to the gateway (services/gui/include/gui/protocol.hpp): reconnects, signs
// in (login, pair, logout), (re)subscribes once the gateway lets this client read, answers
// publish() with the gateway's ack or error, and records when the gateway was last heard
// (its heartbeat comes every `heartbeat_ms`, so a silent link means a stale page).

/// How long a request waits for the gateway's answer before it counts as lost [ms].
const ANSWER_TIMEOUT_MS = 5000;

export class Link {
  constructor(url) {
    this.url = url;
    this.handlers = new Map();   // topic -> Set(fn(data, instance))
    this.rates = new Set();
    this.frames = new Map();     // topic -> fn(header, blob)
    this.pending = new Map();    // id -> {resolve, reject, timer, op}
    this.subs = new Map();       // topic -> max_hz: sent again after every (re)connect and sign-in
    this.subEpoch = 0;           // counts those (re)subscriptions (the first samples after one are cached copies)
    this.nextId = 1;
    this.hello = null;
    this.auth = { required: false, pairing: false };
    this.session = null;         // {user, role, token?, expires_in_s?}; local engineer without auth
    this.authorised = false;     // the gateway answers this client's subscribe and publish
    this.lastRx = 0;             // performance.now() of the last message from the gateway; 0: none
    this.gatewayNowMs = 0;       // the gateway's clock in its last heartbeat [ms since the epoch]
    // Listeners, by event: state (connected: bool), hello (hello), session (session: signed in,
    // or no sign-in needed), signedout (reason), error (an error message without a request id).
    this.listeners = { state: [], hello: [], session: [], signedout: [], error: [] };
    this.connect();
  }
  on(event, fn) { this.listeners[event].push(fn); }
  emit(event, ...args) { for (const fn of this.listeners[event]) fn(...args); }
  get connected() { return !!this.ws && this.ws.readyState === 1; }
  connect() {
    const ws = new WebSocket(this.url);
    ws.binaryType = 'arraybuffer';
    this.ws = ws;
    // Subscriptions go out after "hello" (when no sign-in is needed) or "session": a client
    // that must sign in first would have them refused.
    ws.onopen = () => this.emit('state', true);
    ws.onclose = () => {
      this.authorised = false;
      this.emit('state', false);
      for (const p of this.pending.values()) { clearTimeout(p.timer); p.reject(new Error('connection to the gateway lost')); }
      this.pending.clear();
      setTimeout(() => this.connect(), 1000);
    };
    ws.onmessage = (ev) => this.receive(ev.data);
  }
  send(m) { if (this.connected) this.ws.send(JSON.stringify(m)); }
  sendSubs() {
    this.subEpoch++;
    for (const [topic, hz] of this.subs) this.send({ op: 'subscribe', topic, max_hz: hz });
  }
  setSession(s) {
    this.session = s;
    this.authorised = true;
    this.sendSubs();
    this.emit('session', s);
  }
  receive(raw) {
    this.lastRx = performance.now();
    if (raw instanceof ArrayBuffer) {
      const bytes = new Uint8Array(raw);
      const nl = bytes.indexOf(10);
      const header = JSON.parse(new TextDecoder().decode(bytes.subarray(0, nl)));
      const fn = this.frames.get(header.topic);
      if (fn) fn(header, new Blob([bytes.subarray(nl + 1)], { type: 'image/jpeg' }));
      return;
    }
    const m = JSON.parse(raw);
    switch (m.op) {
      case 'heartbeat': this.gatewayNowMs = m.now_ms; return;
      case 'sample':
        for (const fn of this.handlers.get(m.topic) || []) fn(m.data, m.instance);
        return;
      case 'rates': for (const fn of this.rates) fn(m.topics); return;
      case 'hello': {
        this.hello = m;
        // A gateway without "auth" predates sign-in: every client may do everything.
        this.auth = m.auth || { required: false, pairing: false };
        this.authorised = false;
        if (!this.auth.required) this.setSession(m.session || { user: 'local', role: 'engineer' });
        else if (m.session) this.setSession(m.session);
        else this.session = null;
        this.emit('hello', m);
        return;
      }
      case 'session':
        this.answer(m.id, m, null);
        this.setSession({ user: m.user, role: m.role, token: m.token, expires_in_s: m.expires_in_s });
        return;
      case 'signed_out':
        this.session = null;
        this.authorised = false;
        // The answer to a logout may be this rather than an ack.
        for (const [id, p] of this.pending) if (p.op === 'logout') this.answer(id, m, null);
        this.emit('signedout', m.reason || 'signed out');
        return;
      case 'ack': this.answer(m.id, m, null); return;
      case 'error': {
        const e = new Error(m.error);
        if (m.retry_after_s !== undefined) e.retryAfterS = m.retry_after_s;
        if (!this.answer(m.id, null, e)) this.emit('error', m);
        return;
      }
      default:
    }
  }
  /// Settles the request `id`; false when no request waits for it.
  answer(id, value, error) {
    if (id === undefined || !this.pending.has(id)) return false;
    const p = this.pending.get(id);
    this.pending.delete(id);
    clearTimeout(p.timer);
    if (error) p.reject(error); else p.resolve(value);
    return true;
  }
  /// Sends `m` with a new id; resolves with the gateway's ack or session, rejects with its error
  /// (or when the link is down or the gateway does not answer in time).
  request(m) {
    const id = this.nextId++;
    return new Promise((resolve, reject) => {
      if (!this.connected) { reject(new Error('not connected to the gateway')); return; }
      const timer = setTimeout(() => {
        if (this.pending.delete(id)) reject(new Error(`no answer from the gateway within ${ANSWER_TIMEOUT_MS / 1000} s`));
      }, ANSWER_TIMEOUT_MS);
      this.pending.set(id, { resolve, reject, timer, op: m.op });
      this.ws.send(JSON.stringify({ ...m, id }));
    });
  }
  login(user, password) { return this.request({ op: 'login', user, password }); }
  resume(token) { return this.request({ op: 'login', token }); }
  pair(code) { return this.request({ op: 'pair', code }); }
  logout() { return this.request({ op: 'logout' }); }
  subscribe(topic, fn, maxHz = 0) {
    if (!this.handlers.has(topic)) this.handlers.set(topic, new Set());
    this.handlers.get(topic).add(fn);
    if (!this.subs.has(topic)) {
      this.subs.set(topic, maxHz);
      if (this.authorised) this.send({ op: 'subscribe', topic, max_hz: maxHz });
    }
  }
  watchFrames(topic, fn, maxHz = 2) {
    if (this.frames.size) for (const t of this.frames.keys()) if (t !== topic) this.unwatchFrames(t);
    this.frames.set(topic, fn);
    this.subs.set(topic, maxHz);
    if (this.authorised) this.send({ op: 'subscribe', topic, max_hz: maxHz });
  }
  unwatchFrames(topic) {
    this.frames.delete(topic);
    this.subs.delete(topic);
    this.send({ op: 'unsubscribe', topic });
  }
  publish(topic, data) { return this.request({ op: 'publish', topic, data }); }
  hasTopic(topic) { return !!this.hello && this.hello.topics.some((t) => t.topic === topic); }
  topicsMatching(re) { return this.hello ? this.hello.topics.filter((t) => re.test(t.topic)) : []; }
  /// Milliseconds since the gateway was last heard (Infinity: never, or the link is down).
  silentMs() { return this.connected && this.lastRx ? performance.now() - this.lastRx : Infinity; }
}
