// htn view: the page. It connects to its server's WebSocket (with the token
// of its own URL), keeps every event it is sent, and shows the run at the
// scrubber's position: the latest event while following a run, or any
// earlier one (the tree as it was then, rebuilt from the events before it).
"use strict";

(function () {
  const $ = id => document.getElementById(id);
  const {TreeView, RunModel, STATUSES} = window.HtnTree;
  const {Timeline} = window.HtnTimeline;

  const history = [];
  let cursor = -1;               // the last event applied to the model
  let follow = true;             // the cursor stays on the latest event
  let hello = {};
  let playing = null;
  let frameInfo = null;
  let frameUrl = null;
  let frameSimT = 0;

  const tree = new TreeView($("tree"), $("tree-count"));
  const timeline = new Timeline($("timeline"), $("filters"), $("event-count"), (node, seq) => {
    tree.select(node);
    showAction(tree.model.nodes.get(node));
  });

  for (const s of STATUSES) {
    const span = document.createElement("span");
    const dot = document.createElement("i");
    dot.className = `s-${s}`;
    span.append(dot, s);
    $("legend").appendChild(span);
  }

  // ---------------------------------------------------------------- the connection
  const proto = location.protocol === "https:" ? "wss" : "ws";
  const ws = new WebSocket(`${proto}://${location.host}/ws${location.search}`);
  ws.binaryType = "blob";
  ws.onopen = () => setConn("live", "connected");
  let nextGoal = false;          // a node's view: the next goal's run begins
  ws.onclose = () => {
    if (nextGoal) { setConn("live", "the next goal begins"); setTimeout(() => location.reload(), 300); return; }
    setConn("closed", hello.mode === "log" ? "server stopped" : "view closed: what is shown is final");
  };
  ws.onmessage = msg => {
    if (typeof msg.data !== "string") { showFrame(msg.data); return; }
    const m = JSON.parse(msg.data);
    if (m.type === "hello") {
      hello = m;
      document.body.dataset.mode = m.mode;
      if (m.wall_start) document.body.dataset.wallStart = m.wall_start;
      if (m.title) { $("title").textContent = m.title; document.title = `${m.title} · htn view`; }
      $("camera-panel").hidden = !m.camera;
      // once what came first is on the screen: a run waiting for a page starts now
      requestAnimationFrame(() => setTimeout(() => ws.send(JSON.stringify({type: "ready"})), 0));
    } else if (m.type === "events") {
      receive(m.events, m.from, m.sent);
    } else if (m.type === "frame") {
      frameInfo = m;
    } else if (m.type === "next") {
      nextGoal = true;
    }
  };

  function setConn(state, text) {
    document.body.dataset.state = state;
    $("conn").dataset.state = state;
    $("conn").textContent = text;
  }

  // ---------------------------------------------------------------- events
  function receive(events, from, sent) {
    if (from !== history.length) return;        // the server sends each event once, in order
    history.push(...events);
    timeline.add(events, from, sent);
    if (follow) {
      const bulk = events.length > 200;
      for (let i = from; i < history.length; i++) step(i, !bulk);
      if (bulk) tree.renderAll();
      showAll();
    }
    updateScrubber();
  }

  function step(i, render) {     // apply event i to the model, and to the page
    const node = tree.model.apply(history[i], i);
    cursor = i;
    if (!render) return;
    if (node === "tree") tree.renderAll();
    else if (node) tree.update(node);
  }

  function moveTo(k) {           // the scrubber: the run as it was at event k
    k = Math.max(0, Math.min(k, history.length - 1));
    if (k === cursor + 1) {
      step(k, true);
    } else if (k !== cursor) {
      tree.model = new RunModel();
      for (let i = 0; i <= k; i++) tree.model.apply(history[i], i);
      cursor = k;
      tree.renderAll();
    }
    showAll();
  }

  function showAll() {
    timeline.setCursor(cursor, !follow);
    const m = tree.model;
    showAction(m.current);
    const r = m.summary ? m.summary.detail : "";
    $("result").textContent = r ? (r.startsWith("error") ? "error" : r) : "";
    $("result").dataset.result = r.startsWith("error") ? "error" : r;
    updateScrubber();
    clock();
  }

  function showAction(n) {
    const set = (id, text) => { if ($(id).textContent !== text) $(id).textContent = text; };
    if (!n) { for (const id of ["a-action", "a-phase", "a-attempt", "a-detail"]) set(id, "–"); return; }
    set("a-action", n.kind === "action" ? `${n.step ? `step ${n.step}: ` : ""}${n.task}` : n.task);
    const phases = {execute: n.holds.length ? `execute | hold-monitors: ${n.holds.join(", ")}` : "execute",
                    monitor: "monitor", verified: "verified", aborted: "aborted by the monitor",
                    hold: "aborted: a hold-monitor broke", failed: "failed", retrying: "retrying",
                    interrupted: "interrupted"};
    set("a-phase", phases[n.phase] || n.phase || (n.kind === "action" ? "pending" : n.shown));
    $("a-phase").dataset.phase = n.phase;
    set("a-attempt", n.attempt ? `${n.attempt}${n.retries ? ` (${n.retries} retried)` : ""}` : "–");
    set("a-detail", n.detail || n.note || "–");
  }

  function clock() {
    const ev = history[cursor];
    if (!ev) return;
    const over = tree.model.summary !== null;
    let wall = Number(ev.t || 0), sim = Number(ev.sim_t || 0);
    if (follow && hello.mode === "live" && !over && hello.wall_start) {
      wall = Date.now() / 1000 - hello.wall_start;
      sim = Math.max(sim, frameSimT);
    }
    const text = `sim ${sim.toFixed(2)} s · wall ${wall.toFixed(2)} s`;
    $("a-time").textContent = text;
    $("clock").textContent = over && follow ? "run over" : (follow ? "live" : "replay");
  }
  setInterval(clock, 250);

  function showFrame(blob) {
    const img = $("camera");
    const url = URL.createObjectURL(blob);
    img.onload = () => { if (frameUrl && frameUrl !== url) URL.revokeObjectURL(frameUrl); frameUrl = url; };
    img.src = url;
    img.dataset.frames = Number(img.dataset.frames) + 1;
    if (frameInfo) {
      frameSimT = frameInfo.sim_t;
      $("camera-info").textContent = `frame ${frameInfo.number} · sim ${frameInfo.sim_t.toFixed(2)} s`;
    }
    $("camera-panel").hidden = false;
  }

  // ---------------------------------------------------------------- the scrubber
  function updateScrubber() {
    const range = $("sc-range");
    range.max = Math.max(0, history.length - 1);
    range.value = cursor;
    const ev = history[cursor];
    $("sc-pos").textContent = ev ? `event ${cursor} of ${history.length - 1} · ${ev.event}` +
      (ev.step ? ` · step ${ev.step}` : "") : "";
    $("sc-play").textContent = playing ? "‖" : "▶";
    $("sc-last").setAttribute("aria-pressed", follow ? "true" : "false");
  }

  function pause() { if (playing) { clearInterval(playing); playing = null; } updateScrubber(); }
  function play() {
    if (playing) { pause(); return; }
    follow = false;
    if (cursor >= history.length - 1) moveTo(0);
    playing = setInterval(() => {
      if (cursor >= history.length - 1) { pause(); return; }
      moveTo(cursor + 1);
    }, 1000 / Number($("sc-speed").value));
    updateScrubber();
  }
  const manual = k => { pause(); follow = false; moveTo(k); };
  $("sc-first").onclick = () => manual(0);
  $("sc-back").onclick = () => manual(cursor - 1);
  $("sc-forward").onclick = () => manual(cursor + 1);
  $("sc-play").onclick = play;
  $("sc-fault").onclick = () => {
    const k = history.findIndex((ev, i) => i > cursor && ev.event === "fault");
    if (k >= 0) { manual(k); if (history[k].node !== undefined) tree.select(history[k].node); }
  };
  $("sc-last").onclick = () => { pause(); moveTo(history.length - 1); follow = true; showAll(); };
  $("sc-range").oninput = e => manual(Number(e.target.value));
  $("sc-speed").onchange = () => { if (playing) { pause(); play(); } };
  document.addEventListener("keydown", e => {
    if (e.target.tagName === "INPUT" || e.target.tagName === "SELECT") return;
    const keys = {ArrowLeft: () => manual(cursor - 1), ArrowRight: () => manual(cursor + 1),
                  Home: () => manual(0), End: () => $("sc-last").onclick(), " ": play,
                  f: () => $("sc-fault").onclick()};
    if (keys[e.key]) { e.preventDefault(); keys[e.key](); }
  });

  $("expand-all").onclick = () => tree.setAll(true);
  $("collapse-all").onclick = () => tree.setAll(false);
  $("show-running").onclick = () => { if (tree.model.current) tree.select(tree.model.current.id); };
})();
