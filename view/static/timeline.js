// htn view: the event timeline. One row per log event (the synthetic tree of
// an old log excepted), filterable by kind, faults highlighted; clicking a
// row selects its node in the tree. Each row records when it was put into
// the page (data-shown, ms since the epoch) beside the event's own t.
"use strict";

class Timeline {
  constructor(el, filtersEl, countEl, onSelect) {
    this.el = el;
    this.filtersEl = filtersEl;
    this.countEl = countEl;
    this.rows = [];              // by event number (null: not listed)
    this.kinds = new Map();      // kind -> [count, count element]
    this.hidden = new Set();
    this.cursor = -1;
    this.listed = 0;
    this.queue = [];             // chunks of rows still to put in
    this.stick = true;           // following the newest event (scrolled to the bottom)
    this.pending = false;
    // a scroll the user makes decides whether the list follows the newest event
    this.scrolling = false;
    el.addEventListener("scroll", () => {
      if (this.scrolling) { this.scrolling = false; return; }
      this.stick = el.scrollTop + el.clientHeight >= el.scrollHeight - 60;
    }, {passive: true});
    el.addEventListener("click", e => {
      const row = e.target.closest(".ev");
      if (!row) return;
      for (const r of this.el.querySelectorAll(".ev.selected")) r.classList.remove("selected");
      row.classList.add("selected");
      if (row.dataset.node !== undefined) onSelect(Number(row.dataset.node), Number(row.dataset.seq));
    });
  }

  add(events, from, sent) {      // events[k] is event number from + k
    if (events.length <= CHUNK && !this.queue.length) { this.insert(events, from, sent); return; }
    // many at once (a log, or a page that connects late): the tree is drawn
    // first, the rows follow in chunks, each in a task of its own
    for (let k = 0; k < events.length; k += CHUNK) this.queue.push([events.slice(k, k + CHUNK), from + k, sent]);
    if (this.queue.length === Math.ceil(events.length / CHUNK)) this.drain();
  }

  drain() {                      // after the next frame is on the screen
    requestAnimationFrame(() => requestAnimationFrame(() => setTimeout(() => {
      const [events, from, sent] = this.queue.shift();
      this.insert(events, from, sent);
      if (this.queue.length) this.drain();
    }, 0)));
  }

  insert(events, from, sent) {
    const now = Date.now();
    const html = [], added = [], counts = new Map();
    events.forEach((ev, k) => {
      const seq = from + k;
      this.rows[seq] = null;
      if (ev.synthetic) return;
      const future = this.cursorFixed && seq > this.cursor;
      html.push(rowHtml(ev, seq, now, sent, future, this.hidden.has(ev.event), seq === this.cursor && this.cursorFixed));
      added.push(seq);
      counts.set(ev.event, (counts.get(ev.event) || 0) + 1);
    });
    this.el.insertAdjacentHTML("beforeend", html.join(""));
    const rows = this.el.children, first = rows.length - added.length;
    added.forEach((seq, k) => { this.rows[seq] = rows[first + k]; });
    for (const [kind, n] of counts) this.count(kind, n);
    this.listed += added.length;
    this.countEl.textContent = ` ${this.listed}`;
    this.later();
  }

  later() {                      // layout work once a frame, never once an event
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => {
      this.pending = false;
      if (this.cursorFixed) {
        const row = this.rows[this.cursor];
        if (row) row.scrollIntoView({block: "nearest"});
      } else if (this.stick && this.el.scrollTop + this.el.clientHeight < this.el.scrollHeight) {
        this.scrolling = true;
        this.el.scrollTop = this.el.scrollHeight;
      }
    });
  }

  count(kind, n) {
    let entry = this.kinds.get(kind);
    if (!entry) {
      const label = document.createElement("label");
      const box = document.createElement("input");
      box.type = "checkbox";
      box.checked = true;
      box.dataset.kind = kind;
      box.addEventListener("change", () => this.filter(kind, !box.checked));
      const n = document.createElement("span");
      label.append(box, `${kind} `, n);
      this.filtersEl.appendChild(label);
      entry = [0, n];
      this.kinds.set(kind, entry);
    }
    entry[0] += n;
    entry[1].textContent = entry[0];
  }

  filter(kind, hide) {
    if (hide) this.hidden.add(kind); else this.hidden.delete(kind);
    for (const r of this.rows) if (r && r.dataset.kind === kind) r.hidden = hide;
  }

  setCursor(k, fixed) {          // rows after k are the future; k is the current one
    const old = this.cursor;
    this.cursorFixed = fixed;
    const lo = Math.max(0, Math.min(old, k) - 1), hi = Math.max(old, k) + 1;
    const all = this.cursor < 0 || Math.abs(k - old) > 2000;
    const [a, b] = all ? [0, this.rows.length - 1] : [lo, Math.min(hi, this.rows.length - 1)];
    for (let i = a; i <= b; i++) {
      const r = this.rows[i];
      if (!r) continue;
      r.classList.toggle("future", fixed && i > k);
      r.classList.toggle("current", fixed && i === k);
    }
    this.cursor = k;
    this.later();
  }
}

const CHUNK = 1500;              // rows put into the page in one task, at most

function rowHtml(ev, seq, shown, sent, future, hidden, current) {
  const esc = window.HtnTree.esc;
  const node = ev.node !== undefined && ev.node !== null ? ` data-node="${ev.node}"` : "";
  const head = [ev.step !== null && ev.step !== undefined ? `${ev.step}` : "",
                ev.event === "fault" ? `${ev.kind}:` : "", ev.action || ""].filter(Boolean).join(" ");
  const detail = detailOf(ev);
  return `<div class="ev${future ? " future" : ""}${current ? " current" : ""}" role="listitem" data-seq="${seq}" ` +
    `data-kind="${esc(ev.event)}" data-t="${Number(ev.t || 0)}" data-shown="${shown}"` +
    `${sent ? ` data-sent="${sent}"` : ""}${node}${hidden ? " hidden" : ""}>` +
    `<span class="n">#${seq}</span>` +
    `<span class="t" title="wall ${Number(ev.t || 0).toFixed(3)} s">${Number(ev.sim_t || 0).toFixed(2)}s</span>` +
    `<span class="k">${esc(ev.event)}</span>` +
    `<span class="w" title="${esc(`${head} ${detail}`.trim())}">${esc(head ? head + " " : "")}` +
    `<span class="d">${esc(detail)}</span></span></div>`;
}

function detailOf(ev) {
  if (ev.event === "header") {
    const plan = (ev.plan || "").split("/").pop();
    return `${plan} on ${ev.robot}${ev.faults ? `, faults ${ev.faults}` : ""}, seed ${ev.seed}`;
  }
  if (ev.event === "summary") {
    return `${ev.detail}: ${ev.verified ?? "?"} of ${ev.steps ?? "?"} steps verified, ` +
      `${ev.retries ?? 0} retries, ${ev.replans ?? 0} replans`;
  }
  return ev.detail || "";
}

window.HtnTimeline = {Timeline, detailOf};
