// htn view: the run model (built from log events alone) and the task-tree view.
//
// The model follows the log's events (README, "the event log"): `tree` events
// give the task tree and each graft (new nodes under `parent`, replacing the
// subtrees of `replaces`), and every event about an action names its node.
// A compound task's status is derived from its children (replaced subtrees
// left out): running while any child runs, failed / aborted / interrupted when
// a child ended so, verified when all children are.
"use strict";

const STATUSES = ["pending", "running", "finished", "verified", "retrying", "aborted",
                  "failed", "interrupted"];
const ACTIVE = new Set(["running", "finished", "retrying"]);
const MAX_INDENT = 30;        // levels indented; deeper ones say their depth

class RunModel {
  constructor() {
    this.nodes = new Map();
    this.root = null;
    this.header = null;
    this.summary = null;
    this.current = null;      // the node of the latest action event
    this.last = null;         // the latest event
    this.replaced = 0;
  }

  apply(ev, seq) {
    this.last = ev;
    const kind = ev.event;
    if (kind === "header") { this.header = ev; return null; }
    if (kind === "summary") { this.summary = ev; return null; }
    if (kind === "tree") { this.addTree(ev, seq); return "tree"; }
    const node = ev.node === undefined || ev.node === null ? null : this.nodes.get(ev.node);
    if (!node) return null;
    if (ev.step !== null && ev.step !== undefined) node.step = ev.step;
    if (kind !== "fault") this.current = node;
    switch (kind) {
      case "start": node.status = "running"; node.phase = "execute"; node.detail = ""; break;
      case "feedback": node.detail = ev.detail; break;
      case "finished": node.status = "finished"; node.phase = "monitor"; node.detail = ev.detail; break;
      case "verified": node.status = "verified"; node.phase = "verified"; node.detail = ev.detail; break;
      case "aborted": node.status = "aborted"; node.phase = ev.hold ? "hold" : "aborted";
        node.detail = ev.detail; break;
      case "failed": node.status = "failed"; node.phase = "failed"; node.detail = ev.detail; break;
      case "retrying": node.status = "retrying"; node.phase = "retrying"; node.retries += 1;
        node.detail = ev.detail; break;
      case "interrupted": node.status = "interrupted"; node.phase = "interrupted";
        node.detail = ev.detail; break;
      case "fault": node.faults.push({kind: ev.kind, detail: ev.detail, seq}); break;
      default: node.note = ev.detail;        // replanned, replan_failed, an event of a plugin
    }
    if (ev.attempt) node.attempt = ev.attempt;
    node.events += 1;
    return node;
  }

  addTree(ev, seq) {
    const graft = this.root !== null;
    const tops = [];
    for (const n of ev.nodes) {
      const node = {
        id: n.id, parent: n.parent, task: n.task, label: n.label || "", method: n.method,
        branch: n.branch, step: n.step, holds: n.holds || [], children: [], depth: 0,
        kind: n.step !== undefined ? "action" : (n.parent === null ? "root" : "task"),
        status: "pending", shown: "pending", phase: "", detail: "", note: "", attempt: 0,
        retries: 0, faults: [], events: 0, replaced: null, grafted: graft ? seq : null,
      };
      this.nodes.set(n.id, node);
      if (n.parent === null || n.parent === undefined) { if (!this.root) this.root = node; continue; }
      const parent = this.nodes.get(n.parent);
      if (!parent) continue;
      node.depth = parent.depth + 1;
      if (graft && n.parent === ev.parent) tops.push(node); else parent.children.push(node);
    }
    if (!graft) return;
    const holder = this.nodes.get(ev.parent);
    if (!holder) return;
    let at = -1;
    for (const id of ev.replaces || []) {
      const old = this.nodes.get(id);
      if (!old) continue;
      old.replaced = seq;
      this.replaced += 1;
      at = Math.max(at, holder.children.indexOf(old));
    }
    holder.children.splice(at < 0 ? holder.children.length : at + 1, 0, ...tops);
  }

  derive(node) {
    if (node.kind === "action") return node.status;
    const kids = node.children.filter(c => c.replaced === null);
    // decomposed into nothing: nothing to do (an undecomposed task never runs)
    if (!kids.length) return node.method !== undefined && node.method !== null ? "verified" : "pending";
    let verified = 0, started = false, worst = null;
    for (const c of kids) {
      const s = c.shown;
      if (c.kind === "task" && !c.children.length) { verified += 1; continue; }  // nothing to do
      if (ACTIVE.has(s)) return "running";
      if (s === "verified") verified += 1;
      if (s !== "pending") started = true;
      if (s === "failed" || (s === "aborted" && worst !== "failed") ||
          (s === "interrupted" && worst === null)) worst = s;
    }
    if (worst) return worst;
    if (verified === kids.length) return "verified";
    return started ? "running" : "pending";
  }

  deriveAll() {                      // children before parents
    const order = this.walk();
    for (let i = order.length - 1; i >= 0; i--) {
      order[i].shown = this.derive(order[i]);
      this.settle(order[i]);
    }
  }

  deriveUp(node) {                   // the node and its ancestors; returns those that changed
    const changed = [];
    for (let n = node; n; n = this.nodes.get(n.parent)) {
      const s = this.derive(n);
      const settled = this.settle(n);
      changed.push(...settled);
      if (s !== n.shown || n === node || settled.length) { n.shown = s; changed.push(n); }
      else break;
      if (n.parent === null || n.parent === undefined) break;
    }
    return changed;
  }

  settle(node) {                     // a task decomposed into nothing: done once passed
    const changed = [];
    let passed = node.shown === "verified";
    for (let i = node.children.length - 1; i >= 0; i--) {
      const c = node.children[i];
      if (c.kind === "task" && !c.children.length && c.method !== undefined && c.method !== null) {
        const s = passed ? "verified" : "pending";
        if (c.shown !== s) { c.shown = s; changed.push(c); }
      } else if (c.shown !== "pending") {
        passed = true;
      }
    }
    return changed;
  }

  walk() {                           // every node, depth first in order
    const out = [];
    if (!this.root) return out;
    const stack = [this.root];
    while (stack.length) {
      const n = stack.pop();
      out.push(n);
      for (let i = n.children.length - 1; i >= 0; i--) stack.push(n.children[i]);
    }
    return out;
  }

  ancestors(node) {
    const out = [];
    for (let n = this.nodes.get(node.parent); n; n = this.nodes.get(n.parent)) out.push(n);
    return out;
  }
}

class TreeView {
  constructor(el, countEl) {
    this.el = el;
    this.countEl = countEl;
    this.model = new RunModel();
    this.rows = new Map();
    this.choice = new Map();      // id -> open, as the user chose
    this.forced = new Set();      // the running path: opened whenever the running action moves
    this.selected = null;
    el.addEventListener("click", e => this.onClick(e));
  }

  isOpen(node) {
    if (this.choice.has(node.id)) return this.choice.get(node.id);
    if (this.forced.has(node.id)) return true;
    if (node.replaced !== null) return false;
    return node.depth < 2 || this.model.nodes.size <= 200;
  }

  focus(node) {                   // open the path to node (a node new on it opens, even if closed)
    const path = new Set(this.model.ancestors(node).map(n => n.id));
    for (const id of path) if (!this.forced.has(id)) this.choice.delete(id);
    this.forced = path;
  }

  renderAll() {                   // the rows of the open part of the tree, as one HTML text
    const model = this.model;
    model.deriveAll();
    if (model.current) this.focus(model.current);
    this.rows.clear();
    this.el.innerHTML = "";
    if (model.root) this.insertRows(model.root, null);
    if (this.selected !== null && this.rows.has(this.selected)) this.rows.get(this.selected).classList.add("selected");
    const actions = [...model.nodes.values()].filter(n => n.kind === "action").length;
    this.countEl.textContent = `${model.nodes.size} nodes · ${actions} actions` +
      (model.replaced ? ` · ${model.replaced} replaced` : "");
  }

  insertRows(top, after) {        // rows for top's open subtree (top's own if after is null)
    const html = [], order = [];
    const stack = after === null ? [[top, this.inReplaced(top)]] :
      (this.isOpen(top) ? top.children.map(c => [c, this.inReplaced(c)]).reverse() : []);
    while (stack.length) {
      const [n, gone] = stack.pop();
      html.push(this.rowHtml(n, gone));
      order.push(n);
      if (this.isOpen(n)) {
        for (let i = n.children.length - 1; i >= 0; i--) {
          const c = n.children[i];
          stack.push([c, gone || c.replaced !== null]);
        }
      }
    }
    if (after === null) this.el.insertAdjacentHTML("beforeend", html.join(""));
    else after.insertAdjacentHTML("afterend", html.join(""));
    let row = after === null ? this.el.lastElementChild : after.nextElementSibling;
    if (after === null) for (let i = 1; i < order.length; i++) row = row.previousElementSibling;
    for (const n of order) { this.rows.set(n.id, row); row = row.nextElementSibling; }
  }

  inReplaced(n) {
    for (let a = n; a; a = this.model.nodes.get(a.parent)) if (a.replaced !== null) return true;
    return false;
  }

  parts(n) {                      // what a row shows of a node
    const open = this.isOpen(n);
    let meta = n.kind === "action" ? (n.step ? `step ${n.step}` : "") :
      (n.method ? `${n.method} · ${n.branch}` : (n.kind === "task" ? "not decomposed" : ""));
    if (n.kind === "action" && n.attempt > 1) meta += ` · try ${n.attempt}`;
    const badges = [];
    if (n.retries) badges.push(["retry", `↻ ${n.retries} ${n.retries === 1 ? "retry" : "retries"}`, ""]);
    if (n.faults.length) badges.push(["fault", `⚡ ${n.faults.map(f => f.kind).join(", ")}`,
                                      n.faults.map(f => `${f.kind}: ${f.detail}`).join("\n")]);
    if (n.replaced !== null) badges.push(["replaced", `replaced at #${n.replaced}`,
                                          "re-planned: the grafted subtree below replaces it"]);
    const up = this.model.nodes.get(n.parent);
    if (n.grafted !== null && up && up.grafted === null) badges.push(["grafted", `grafted at #${n.grafted}`,
                                                                        "the repair's new subtree"]);
    return {glyph: n.children.length ? (open ? "▾" : "▸") : "", open, meta, badges};
  }

  rowHtml(n, inReplaced) {
    const p = this.parts(n);
    const attrs = [`class="node d${Math.min(n.depth, MAX_INDENT)}"`, `data-node="${n.id}"`,
                   `data-kind="${n.kind}"`, `data-depth="${n.depth}"`, `data-status="${n.shown}"`,
                   `data-faults="${n.faults.length}"`, `role="treeitem"`];
    if (n.children.length) attrs.push(`aria-expanded="${p.open}"`);
    if (inReplaced) attrs.push("data-replaced");
    if (n.grafted !== null) attrs.push("data-grafted");
    const deep = n.depth > MAX_INDENT ? `<span class="deep">${n.depth}</span>` : "";
    const badges = p.badges.map(([cls, label, title]) =>
      `<span class="badge ${cls}" title="${esc(title)}">${esc(label)}</span>`).join("");
    return `<div ${attrs.join(" ")}><span class="tg">${p.glyph}</span>${deep}<span class="dot"></span>` +
      `<span class="task" title="${esc(n.label)}">${esc(n.task)}</span>` +
      `<span class="meta">${esc(p.meta)}</span><span class="badges">${badges}</span></div>`;
  }

  fill(row, n) {                  // what changes as events come
    const p = this.parts(n);
    if (row.dataset.status !== n.shown) row.dataset.status = n.shown;
    const tg = row.firstChild;
    if (tg.textContent !== p.glyph) tg.textContent = p.glyph;
    if (n.children.length) row.setAttribute("aria-expanded", p.open ? "true" : "false");
    const meta = row.querySelector(".meta");
    if (meta.textContent !== p.meta) meta.textContent = p.meta;
    const badges = row.querySelector(".badges");
    const key = JSON.stringify(p.badges);
    if ((badges.dataset.key || "[]") !== key) {
      badges.dataset.key = key;
      badges.replaceChildren(...p.badges.map(([cls, label, title]) => {
        const b = document.createElement("span");
        b.className = `badge ${cls}`;
        b.textContent = label;
        if (title) b.title = title;
        return b;
      }));
      row.dataset.faults = n.faults.length;
    }
  }

  update(node) {                  // after an event about node: it and its ancestors
    const changed = this.model.deriveUp(node);
    for (const n of changed) { const row = this.rows.get(n.id); if (row) this.fill(row, n); }
    if (node === this.model.current) {
      const before = this.forced;
      this.focus(node);
      // the nodes that opened or closed with the running path, shallowest first
      const moved = [...before].filter(id => !this.forced.has(id))
        .concat([...this.forced].filter(id => !before.has(id)))
        .map(id => this.model.nodes.get(id)).filter(n => n).sort((a, b) => a.depth - b.depth);
      const done = new Set();
      for (const n of moved) {
        if (this.model.ancestors(n).some(a => done.has(a.id))) continue;
        this.refreshBelow(n);
        done.add(n.id);
      }
    }
  }

  refreshBelow(node) {            // node's subtree drawn again, open where it is open
    const row = this.rows.get(node.id);
    if (!row) return;
    this.fill(row, node);
    const stack = [...node.children];
    while (stack.length) {
      const n = stack.pop();
      const r = this.rows.get(n.id);
      if (!r) continue;                 // not drawn: neither is anything below it
      r.remove();
      this.rows.delete(n.id);
      stack.push(...n.children);
    }
    this.insertRows(node, row);
    if (this.selected !== null && this.rows.has(this.selected)) this.rows.get(this.selected).classList.add("selected");
  }

  setAll(open) {
    for (const n of this.model.nodes.values()) if (n.children.length) this.choice.set(n.id, open);
    if (this.model.root) this.refreshBelow(this.model.root);
  }

  select(id, scroll = true) {     // open the way to node id, and mark it
    const node = this.model.nodes.get(id);
    if (!node) return;
    const path = this.model.ancestors(node).reverse();        // the root first
    const closed = path.find(a => !this.isOpen(a));
    for (const a of path) this.choice.set(a.id, true);
    if (closed) this.refreshBelow(closed);
    if (this.selected !== null && this.rows.has(this.selected)) this.rows.get(this.selected).classList.remove("selected");
    this.selected = id;
    const row = this.rows.get(id);
    if (row) { row.classList.add("selected"); if (scroll) row.scrollIntoView({block: "center"}); }
  }

  onClick(e) {
    const row = e.target.closest(".node");
    if (!row) return;
    const node = this.model.nodes.get(Number(row.dataset.node));
    if (!node) return;
    if (e.target.classList.contains("tg") && node.children.length) {
      this.choice.set(node.id, !this.isOpen(node));
      this.refreshBelow(node);
      return;
    }
    this.select(node.id, false);
  }
}

function esc(text) {
  return String(text).replace(/[&<>"']/g, c => ({"&": "&amp;", "<": "&lt;", ">": "&gt;",
                                                 '"': "&quot;", "'": "&#39;"}[c]));
}

window.HtnTree = {RunModel, TreeView, STATUSES, esc};
