(function () {
  var plan = JSON.parse(document.getElementById("eos-plan").textContent);
  var slider = document.getElementById("eos-time");
  var button = document.getElementById("eos-play");
  slider.max = String(plan.duration);
  slider.step = String(1 / plan.fps);
  var target = null;
  function parseHash() {
    var h = window.location.hash.replace(/^#/, "");
    var m = /(?:^|&)t=([0-9.]+)/.exec(h);
    if (m) { return parseFloat(m[1]); }
    m = /(?:^|&)cycle=([0-9]+)/.exec(h);
    if (m) {
      var n = parseInt(m[1], 10);
      for (var i = 0; i < plan.cycles.length; i++) {
        if (plan.cycles[i].seq === n) { return plan.cycles[i].t1; }
      }
      return plan.duration;
    }
    return null;
  }
  function animator() {
    if (typeof viewer === "undefined" || !viewer.animator) { return null; }
    return viewer.animator.actions.length ? viewer.animator : null;
  }
  function now(a) {
    return a.actions.reduce(function (m, x) { return Math.max(m, x.time); }, 0);
  }
  function cycleAt(t) {
    var lo = 0, hi = plan.cycles.length - 1, found = -1;
    while (lo <= hi) {
      var mid = (lo + hi) >> 1;
      // cycle k covers (t0, t1]: at its t1 the cycle is done and shown
      if (plan.cycles[mid].t0 < t - 1e-9) { found = mid; lo = mid + 1; } else { hi = mid - 1; }
    }
    return found < 0 ? null : plan.cycles[found];
  }
  function show(t) {
    var c = cycleAt(t);
    slider.value = String(t);
    document.getElementById("eos-clock").textContent = t.toFixed(1) + " / " + plan.duration.toFixed(1) + " s";
    document.getElementById("eos-cycle").textContent = c === null ? "before the first cycle" :
      "cycle " + c.seq + "/" + plan.cycles.length + "  " + c.stage + "  " + (c.chosen || "-") +
      " [" + (c.outcome || "-") + "]";
    document.getElementById("eos-detail").textContent = c === null ? "" : c.detail;
    document.body.dataset.eosCycle = c === null ? "0" : String(c.seq);
  }
  function seek(a, t) {
    a.pause();
    a.seek(t);
    a.display_progress(t);
    button.textContent = "play";
    show(t);
  }
  var ready = false;
  window.setInterval(function () {
    var a = animator();
    if (a === null) { return; }
    if (!ready) {
      ready = true;
      target = parseHash();
      if (target !== null) { seek(a, target); }
      document.body.dataset.eosReady = "1";
    }
    if (a.playing) { show(now(a)); button.textContent = "pause"; } else { button.textContent = "play"; }
  }, 100);
  window.addEventListener("hashchange", function () {
    var a = animator(), t = parseHash();
    if (a !== null && t !== null) { seek(a, t); }
  });
  slider.addEventListener("input", function () {
    var a = animator();
    if (a !== null) { seek(a, parseFloat(slider.value)); }
  });
  button.addEventListener("click", function () {
    var a = animator();
    if (a === null) { return; }
    if (a.playing) { a.pause(); return; }
    if (now(a) >= plan.duration - 1e-6) { a.reset(); }
    a.play();
  });
})();
