// The play page: draws the streamed table, turns a drag into a shot, shows score and belief.
"use strict";
(function () {
  const MODE_COLOURS = { left: "#2f6fd6", middle: "#7a7f87", right: "#d9622b" };
  const M = 20, S = 300; // canvas margin (px) and scale (px per metre)
  const canvas = document.getElementById("table");
  const ctx = canvas.getContext("2d");
  const statusEl = document.getElementById("status");
  // Exposed for tests and benchmarks: page state and the measured frame rate.
  const lili = (window.lili = { connected: false, ready: false, over: false, shots: 0,
                                results: [], errors: [], cancelled: 0, ended: null, fps: 0,
                                frames: 0, ws: null });
  // A press must move this far (table metres) before its release shoots: a click does not.
  const MIN_DRAG = 0.08;
  let geo = null, speed = 1, prev = null, cur = null, curTime = 0, aim = null, press = null;
  let flash = null, probe = null, beliefs = [], paper = null, algo = "", pending = false;
  let resetTimer = null, ws = null;

  const X = (x) => M + (x + geo.half_width) * S;
  const Y = (y) => M + (geo.half_length - y) * S;

  function setStatus(text, isError) {
    statusEl.textContent = text;
    statusEl.className = isError ? "error" : "";
  }

  // One game per connection: a new game is a new connection (the server starts a new session
  // and a new record; the old one's rows stay as they are).
  function connect() {
    if (ws) { ws.onclose = null; ws.close(); }
    Object.assign(lili, { connected: false, ready: false, over: false, shots: 0, results: [],
                          errors: [], cancelled: 0, ended: null });
    beliefs = []; aim = null; press = null; flash = null; pending = false; cur = prev = null;
    document.getElementById("result").hidden = true;
    setStatus("connecting…");
    const sock = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws`);
    ws = lili.ws = sock;
    sock.onopen = () => { lili.connected = true; };
    sock.onclose = () => {
      lili.connected = false; lili.ready = false;
      if (!lili.over) setStatus("disconnected: press New game (or reload the page)", true);
    };
    sock.onmessage = (ev) => {
      const msg = JSON.parse(ev.data);
      if (msg.type === "init") onInit(msg);
      else if (msg.type === "frame") { pending = false; onFrame(msg); }
      else if (msg.type === "result") onResult(msg);
      else if (msg.type === "game_over") onGameOver(msg);
      else if (msg.type === "error") onError(msg);
    };
  }
  document.getElementById("new-game").addEventListener("click", connect);

  function onError(msg) {
    lili.errors.push(msg.error);
    setStatus(msg.error, true);
    // A shot the server refused was not played: the visitor may shoot again.
    if (pending && !lili.over) { pending = false; lili.ready = true; }
  }

  const AIM_HINT = "your shot: press on the table, drag towards your target, release";

  function startPosition() {
    return { puck: geo.puck_start, paddle: 0, striker: [geo.puck_start[0],
      geo.puck_start[1] + geo.puck_radius + geo.paddle_radius + 0.01] };
  }

  // The table as it is before every shot: the puck back at its start, the paddles home.
  function resetTable() {
    if (resetTimer !== null) { clearTimeout(resetTimer); resetTimer = null; }
    if (geo) { cur = prev = startPosition(); curTime = 0; }
  }

  function onInit(msg) {
    geo = msg.table;
    speed = msg.speed || 1;
    algo = msg.algo;
    paper = msg.paper;
    document.getElementById("algo").textContent = msg.algo;
    document.getElementById("trained").textContent =
      `(robot blocker trained on ${msg.interactions} interactions)`;
    probe = msg.probe;
    const note = document.getElementById("probe-note");
    if (probe) {
      note.textContent = `The belief is a probe on the robot's ${msg.latent_dim}-D latent ` +
        `predicting the mode of your next shot, fitted on ${probe.n_fit} simulated shots ` +
        `(held-out accuracy ${Math.round(100 * probe.accuracy)}% on ${probe.n_test}). Above: ` +
        `the latent's two principal components; the ring is what it believes now.`;
    } else {
      note.textContent = `${msg.algo} has no latent: it cannot form a belief about your next shot.`;
    }
    lili.total = msg.shots;
    showScore(msg.score);
    showBelief(msg.belief);
    drawAims();
    drawLatent();
    resetTable();
    lili.ready = true;
    setStatus(AIM_HINT);
  }

  function onFrame(msg) {
    prev = msg.t === 0 ? msg : cur;
    cur = msg;
    curTime = performance.now();
  }

  function onResult(msg) {
    lili.results.push(msg);
    lili.shots = msg.score.shots;
    flash = { text: msg.blocked ? "blocked" : "goal!", scored: !msg.blocked, until: performance.now() + 900 };
    showScore(msg.score);
    showBelief(msg.belief);
    drawAims();
    if (!msg.done) {
      resetTimer = setTimeout(resetTable, 900);
      lili.ready = true;
      setStatus(`shot ${msg.shot} (${msg.mode}): ${msg.blocked ? "the robot blocked it" : "you scored"}. ` +
        "Your next shot: press, drag, release");
    }
  }

  function onGameOver(msg) {
    lili.over = true;
    lili.ready = false;
    pending = false;
    const s = msg.score;
    if (msg.ended) {
      lili.ended = msg.ended;
      setStatus(`Recording failed: ${msg.ended}. Press New game to try again.`, true);
    } else {
      setStatus(`Game over: you scored ${s.goals} of ${s.shots}; the robot blocked ${s.blocks}. ` +
        "Press New game to play again.");
    }
    showResult(s);
  }

  // The visitor's game beside the paper's human study (Section 5: an expert human, 40 shots).
  function showResult(score) {
    const body = document.querySelector("#study tbody");
    const names = { sac: "SAC", "lili-no-influence": "LILI (no influence)" };
    const rows = [[`${algo}, this page`, "you", score.blocks, score.shots, true]];
    for (const [key, blocks] of Object.entries(paper ? paper.blocks : {})) {
      rows.push([`${names[key] || key}, paper`, "expert human", blocks, paper.shots, false]);
    }
    body.innerHTML = "";
    for (const [who, striker, b, n, you] of rows) {
      const pct = n ? ` (${Math.round((100 * b) / n)}%)` : "";
      const tr = document.createElement("tr");
      if (you) tr.className = "you";
      for (const text of [who, striker, `${b}/${n}${pct}`]) {
        const td = document.createElement("td"); td.textContent = text; tr.appendChild(td);
      }
      body.appendChild(tr);
    }
    document.getElementById("study-note").textContent = paper ? `${paper.lili}.` : "";
    const panel = document.getElementById("result");
    panel.hidden = false;
    panel.scrollIntoView({ block: "nearest" });
  }

  function showScore(score) {
    for (const [mode, [b, n]] of Object.entries(score.by_mode)) {
      const row = document.querySelector(`tr[data-mode=${mode}]`);
      row.querySelector(".b").textContent = b;
      row.querySelector(".g").textContent = n - b;
      row.querySelector(".s").textContent = n;
    }
    document.getElementById("blocks").textContent = score.blocks;
    document.getElementById("goals").textContent = score.goals;
    document.getElementById("total-blocks").textContent = score.blocks;
    document.getElementById("total-goals").textContent = score.goals;
    document.getElementById("shots").textContent = score.shots;
    document.getElementById("remaining").textContent = `${score.of - score.shots} of ${score.of} shots left`;
  }

  function showBelief(belief) {
    const bars = document.getElementById("bars");
    const note = document.getElementById("belief-note");
    bars.innerHTML = "";
    if (!geo) return;
    if (!belief) {
      note.textContent = probe
        ? "No belief yet: the robot forms one from your shots, after the first."
        : `${algo} has no latent, so no belief about your next shot.`;
      drawLatent();
      return;
    }
    note.textContent = "Where it expects your next shot:";
    beliefs.push(belief.xy);
    geo.mode_names.forEach((name, i) => {
      const p = belief.probs[i];
      bars.insertAdjacentHTML("beforeend",
        `<span>${name}</span><div><div class="bar ${name}" style="width:${(100 * p).toFixed(0)}%"></div></div>` +
        `<span>${(100 * p).toFixed(0)}%</span>`);
    });
    drawLatent();
  }

  function drawLatent() {
    const c = document.getElementById("latent"), g = c.getContext("2d");
    g.clearRect(0, 0, c.width, c.height);
    if (!probe) return;
    const pts = probe.points.map((p) => p.xy).concat(beliefs);
    const xs = pts.map((p) => p[0]), ys = pts.map((p) => p[1]);
    const x0 = Math.min(...xs), x1 = Math.max(...xs), y0 = Math.min(...ys), y1 = Math.max(...ys);
    const px = (x) => 12 + ((x - x0) / (x1 - x0 || 1)) * (c.width - 24);
    const py = (y) => c.height - 12 - ((y - y0) / (y1 - y0 || 1)) * (c.height - 24);
    for (const p of probe.points) {
      g.fillStyle = MODE_COLOURS[geo.mode_names[p.mode]];
      g.globalAlpha = 0.45;
      g.beginPath(); g.arc(px(p.xy[0]), py(p.xy[1]), 3, 0, 2 * Math.PI); g.fill();
    }
    g.globalAlpha = 1;
    g.strokeStyle = "#1d232a";
    g.beginPath();
    beliefs.forEach((b, i) => (i ? g.lineTo(px(b[0]), py(b[1])) : g.moveTo(px(b[0]), py(b[1]))));
    g.lineWidth = 0.7; g.stroke();
    const last = beliefs[beliefs.length - 1];
    if (last) { g.lineWidth = 2.5; g.beginPath(); g.arc(px(last[0]), py(last[1]), 7, 0, 2 * Math.PI); g.stroke(); }
  }

  function drawAims() {
    const c = document.getElementById("aims"), g = c.getContext("2d");
    g.clearRect(0, 0, c.width, c.height);
    if (!geo) return;
    const n = Math.max(lili.total || 1, 1), lim = geo.aim_limit;
    const px = (i) => 10 + (i / Math.max(n - 1, 1)) * (c.width - 20);
    const py = (a) => c.height / 2 + (a / lim) * (c.height / 2 - 8);
    geo.mode_aims.forEach((a, i) => {
      g.strokeStyle = MODE_COLOURS[geo.mode_names[i]]; g.setLineDash([4, 4]); g.lineWidth = 1;
      g.beginPath(); g.moveTo(0, py(a)); g.lineTo(c.width, py(a)); g.stroke();
    });
    g.setLineDash([]);
    g.fillStyle = "#6b7280"; g.font = "11px system-ui, sans-serif"; g.textAlign = "right";
    g.fillText("left", c.width - 4, py(geo.mode_aims[0]) - 3);
    g.fillText("right", c.width - 4, py(geo.mode_aims[2]) - 3);
    lili.results.forEach((r, i) => {
      g.fillStyle = r.blocked ? "#1a9b5b" : "#c2362f";
      g.beginPath(); g.arc(px(i), py(r.aim), 4, 0, 2 * Math.PI); g.fill();
    });
  }

  // The aim line: straight from the puck with mirror bounces off the side walls.
  function aimPath(a) {
    const wall = geo.half_width - geo.puck_radius;
    let [x, y] = geo.puck_start, dx = Math.sin(a), dy = -Math.cos(a);
    const pts = [[x, y]];
    for (let k = 0; k < 4 && y > geo.ego_y; k++) {
      const tEnd = (geo.ego_y - y) / dy;
      const tWall = dx > 0 ? (wall - x) / dx : dx < 0 ? (-wall - x) / dx : Infinity;
      const t = Math.min(tEnd, tWall);
      x += dx * t; y += dy * t; pts.push([x, y]);
      if (tWall < tEnd) dx = -dx;
    }
    return pts;
  }

  function pointerAim(ev) {
    const [x, y] = pointerXY(ev);
    const dx = x - geo.puck_start[0], dy = Math.min(y - geo.puck_start[1], -1e-3);
    const a = Math.atan2(dx, -dy);
    return Math.max(-geo.aim_limit, Math.min(geo.aim_limit, a));
  }

  // Table metres of a pointer event, unclamped (for the drag length).
  function pointerXY(ev) {
    const r = canvas.getBoundingClientRect();
    return [((ev.clientX - r.left) * (canvas.width / r.width) - M) / S - geo.half_width,
            geo.half_length - ((ev.clientY - r.top) * (canvas.height / r.height) - M) / S];
  }

  canvas.addEventListener("pointerdown", (ev) => {
    if (!lili.ready) return;
    canvas.setPointerCapture(ev.pointerId);
    resetTable();
    press = pointerXY(ev);
    aim = pointerAim(ev);
  });
  canvas.addEventListener("pointermove", (ev) => { if (aim !== null) aim = pointerAim(ev); });
  canvas.addEventListener("pointerup", (ev) => {
    if (aim === null) return;
    const a = pointerAim(ev), [x, y] = pointerXY(ev);
    const drag = Math.hypot(x - press[0], y - press[1]);
    aim = null; press = null;
    if (!lili.ready) return;
    if (drag < MIN_DRAG) {
      lili.cancelled++;
      setStatus(`No shot: drag at least ${Math.round(100 * MIN_DRAG)} cm on the table to shoot ` +
        "(a click does not shoot). " + AIM_HINT);
      return;
    }
    lili.ready = false;
    pending = true;
    ws.send(JSON.stringify({ type: "shoot", aim: a }));
    setStatus("shot in flight…");
  });
  canvas.addEventListener("pointercancel", () => { aim = null; press = null; });

  function label(text, x, y, colour, font) {
    ctx.font = `${font || "12px"} system-ui, sans-serif`; ctx.textAlign = "center";
    ctx.fillStyle = colour; ctx.fillText(text, X(x), Y(y));
  }

  function circle(x, y, r, fill, stroke) {
    ctx.beginPath(); ctx.arc(X(x), Y(y), r * S, 0, 2 * Math.PI);
    ctx.fillStyle = fill; ctx.fill();
    if (stroke) { ctx.strokeStyle = stroke; ctx.lineWidth = 2; ctx.stroke(); }
  }

  function draw(now) {
    ctx.clearRect(0, 0, canvas.width, canvas.height);
    if (!geo) return;
    ctx.fillStyle = "#f9fcfd";
    ctx.fillRect(X(-geo.half_width), Y(geo.half_length), 2 * geo.half_width * S, 2 * geo.half_length * S);
    ctx.strokeStyle = "#3b4a57"; ctx.lineWidth = 4;
    ctx.strokeRect(X(-geo.half_width), Y(geo.half_length), 2 * geo.half_width * S, 2 * geo.half_length * S);
    ctx.lineWidth = 1; ctx.strokeStyle = "#b9c7d0";
    ctx.beginPath(); ctx.moveTo(X(-geo.half_width), Y(0)); ctx.lineTo(X(geo.half_width), Y(0)); ctx.stroke();
    ctx.setLineDash([6, 6]); ctx.strokeStyle = "#6b7f8e";
    ctx.beginPath(); ctx.moveTo(X(-geo.half_width), Y(geo.ego_y)); ctx.lineTo(X(geo.half_width), Y(geo.ego_y)); ctx.stroke();
    ctx.setLineDash([]);
    // Where each mode's noise-free shot arrives.
    geo.mode_names.forEach((name, i) => {
      const end = aimPath(geo.mode_aims[i]).pop();
      ctx.fillStyle = MODE_COLOURS[name]; ctx.globalAlpha = 0.35;
      ctx.fillRect(X(end[0]) - 14, Y(geo.ego_y) + 14, 28, 5); ctx.globalAlpha = 1;
    });
    // The goal the visitor shoots at: the robot's end wall.
    ctx.fillStyle = "#c2362f"; ctx.globalAlpha = 0.18;
    ctx.fillRect(X(-geo.half_width), Y(geo.ego_y - geo.paddle_radius), 2 * geo.half_width * S,
                 (geo.half_length + geo.ego_y - geo.paddle_radius) * S);
    ctx.globalAlpha = 1;
    label("GOAL: get the puck past the robot", 0, -geo.half_length - 0.045, "#7a1d18", "bold 12px");
    if (!cur) return;
    const speedMs = (geo.dt * 1000) / speed;
    const f = Math.min(1, (now - curTime) / speedMs);
    const lerp = (a, b) => a + (b - a) * f;
    const puck = [lerp(prev.puck[0], cur.puck[0]), lerp(prev.puck[1], cur.puck[1])];
    const striker = [lerp(prev.striker[0], cur.striker[0]), lerp(prev.striker[1], cur.striker[1])];
    circle(striker[0], striker[1], geo.paddle_radius, "#c2362f", "#7a1d18");
    circle(lerp(prev.paddle, cur.paddle), geo.ego_y, geo.paddle_radius, "#2f6fd6", "#173d7a");
    circle(puck[0], puck[1], geo.puck_radius, "#1d232a");
    const paddleX = lerp(prev.paddle, cur.paddle);
    label("you: striker", striker[0], striker[1] + geo.paddle_radius + 0.035, "#7a1d18");
    label("robot: blocker", Math.max(-0.3, Math.min(0.3, paddleX)),
          geo.ego_y + geo.paddle_radius + 0.035, "#173d7a");
    if (aim !== null) {
      const pts = aimPath(aim);
      ctx.strokeStyle = "#c2362f"; ctx.lineWidth = 2; ctx.setLineDash([8, 5]);
      ctx.beginPath(); pts.forEach(([x, y], i) => (i ? ctx.lineTo(X(x), Y(y)) : ctx.moveTo(X(x), Y(y))));
      ctx.stroke(); ctx.setLineDash([]);
    }
    if (flash && now < flash.until) {
      ctx.font = "bold 34px system-ui, sans-serif"; ctx.textAlign = "center";
      ctx.fillStyle = flash.scored ? "#c2362f" : "#1a9b5b";
      ctx.fillText(flash.text, canvas.width / 2, Y(-0.3));
    }
  }

  // Frame rate over the last second, measured on the animation loop itself.
  let fpsStart = performance.now(), fpsCount = 0;
  function loop(now) {
    draw(now);
    lili.frames++;
    fpsCount++;
    if (now - fpsStart >= 1000) {
      lili.fps = (1000 * fpsCount) / (now - fpsStart);
      fpsStart = now; fpsCount = 0;
    }
    requestAnimationFrame(loop);
  }
  requestAnimationFrame(loop);
  connect();
})();
