/*
 * The explorer's figures: a small SVG plotting module (embedded ahead of
 * app.js in the same file, see api/CMakeLists.txt).
 *
 * A figure is an <svg class="plot"> with a fixed viewBox that CSS scales
 * to its box.  frame() draws its axes (ticks, labels with units) and
 * returns the maps between data and the viewBox; legend() and key() draw
 * what ties a colour or dash to a meaning inside the figure, so that an
 * exported SVG or PNG carries them; readout() shows the data values under
 * the pointer; zoom() lets the wheel zoom a figure about the pointer.
 * Every element carries its own presentation attributes (no stylesheet),
 * so the serialised SVG is the figure as drawn.
 */
"use strict";

const Plot = (() => {
  const NS = "http://www.w3.org/2000/svg";
  const PAD = { left: 54, right: 12, top: 12, bottom: 36 };
  const INK = "#1b1f24", MUTED = "#4b5560", LINE = "#c9ced4";

  function el(name, attrs, parent) {
    const e = document.createElementNS(NS, name);
    for (const k in attrs)
      e.setAttribute(k, attrs[k]);
    if (parent)
      parent.appendChild(e);
    return e;
  }

  function fmt(v) {
    return Math.abs(v) < 1e-12 ? "0" : String(+v.toPrecision(4));
  }

  function ticks(lo, hi, n) {
    const span = hi - lo || 1;
    const step0 = span / n, mag = Math.pow(10, Math.floor(Math.log10(step0)));
    const step = [1, 2, 5, 10].map((m) => m * mag).find((s) => s >= step0);
    const out = [];
    /* a span of a few ulps: a step below half an ulp of t would not move it */
    for (let t = Math.ceil(lo / step) * step; t <= hi + 1e-12 * span && t + step !== t; t += step)
      out.push(Math.abs(t) < 1e-12 * span ? 0 : t);
    return out;
  }

  /* The smallest and largest of some arrays of numbers. */
  function extent(arrays) {
    let lo = Infinity, hi = -Infinity;
    for (const a of arrays)
      for (const v of a) {
        if (v < lo) lo = v;
        if (v > hi) hi = v;
      }
    return [lo, hi];
  }

  function widen(r) {
    const d = (r[1] - r[0]) || Math.abs(r[0]) || 1;
    return [r[0] - 0.05 * d, r[1] + 0.05 * d];
  }

  /* The plotting area's width and height in svg (side: its legend's column). */
  function inner(svg, side) {
    return [Number(svg.dataset.width) - PAD.left - (side || PAD.right),
            Number(svg.dataset.height) - PAD.top - PAD.bottom];
  }

  /* Clears svg and draws its axes over the ranges xr, yr (widened by 5 %
   * unless exact); labels name the quantity and its unit.  Returns the
   * figure: x(), y() from data to the viewBox, invert() from a pointer
   * event to data, sx, sy (data units per pixel), layer (the data's group)
   * and top (a group drawn over the data: legends, readouts). */
  function frame(svg, o) {
    svg.textContent = "";
    const w = Number(svg.dataset.width), h = Number(svg.dataset.height);
    svg.setAttribute("viewBox", "0 0 " + w + " " + h);
    svg.style.width = w + "px";
    svg.setAttribute("font-family", "system-ui, sans-serif");
    const xr = o.exact ? o.x : widen(o.x), yr = o.exact ? o.y : widen(o.y);
    const [pw, ph] = inner(svg, o.side);
    const p = {
      svg, xr, yr, pw, ph, w, h, pad: PAD, side: o.side || 0,
      xname: o.xname || o.xlabel, yname: o.yname || o.ylabel,
      x: (v) => PAD.left + (v - xr[0]) / (xr[1] - xr[0]) * pw,
      y: (v) => PAD.top + (yr[1] - v) / (yr[1] - yr[0]) * ph,
      sx: (xr[1] - xr[0]) / pw,
      sy: (yr[1] - yr[0]) / ph,
    };
    p.local = (evt) => {
      const pt = svg.createSVGPoint();
      pt.x = evt.clientX;
      pt.y = evt.clientY;
      return pt.matrixTransform(svg.getScreenCTM().inverse());
    };
    p.invert = (evt) => {
      const q = p.local(evt);
      return [xr[0] + (q.x - PAD.left) / pw * (xr[1] - xr[0]),
              yr[1] - (q.y - PAD.top) / ph * (yr[1] - yr[0])];
    };
    p.inside = (evt) => {
      const q = p.local(evt);
      return q.x >= PAD.left && q.x <= PAD.left + pw && q.y >= PAD.top && q.y <= PAD.top + ph;
    };
    el("rect", { width: w, height: h, fill: "#fff" }, svg);
    const axes = el("g", { class: "axes", "font-size": 11, fill: MUTED }, svg);
    el("rect", { x: PAD.left, y: PAD.top, width: pw, height: ph, fill: "none", stroke: LINE }, axes);
    for (const t of ticks(xr[0], xr[1], Math.max(3, Math.round(pw / 70)))) {
      el("line", { x1: p.x(t), x2: p.x(t), y1: PAD.top + ph, y2: PAD.top + ph + 4, stroke: MUTED }, axes);
      el("text", { x: p.x(t), y: PAD.top + ph + 15, "text-anchor": "middle" }, axes).textContent = fmt(t);
    }
    for (const t of ticks(yr[0], yr[1], Math.max(3, Math.round(ph / 55)))) {
      el("line", { x1: PAD.left - 4, x2: PAD.left, y1: p.y(t), y2: p.y(t), stroke: MUTED }, axes);
      el("text", { x: PAD.left - 6, y: p.y(t) + 4, "text-anchor": "end" }, axes).textContent = fmt(t);
    }
    el("text", { x: PAD.left + pw / 2, y: h - 4, "text-anchor": "middle", "font-size": 12,
                 fill: INK, class: "xlabel" }, axes).textContent = o.xlabel;
    el("text", { x: 12, y: PAD.top + ph / 2, "text-anchor": "middle", "font-size": 12, fill: INK,
                 class: "ylabel", transform: "rotate(-90 12 " + (PAD.top + ph / 2) + ")" },
       axes).textContent = o.ylabel;
    const clip = svg.id + "-clip";
    const defs = el("defs", {}, svg);
    el("rect", { x: PAD.left, y: PAD.top, width: pw, height: ph }, el("clipPath", { id: clip }, defs));
    p.layer = el("g", { class: "data", "clip-path": "url(#" + clip + ")" }, svg);
    p.top = el("g", { class: "over" }, svg);
    svg.classList.remove("stale");
    return p;
  }

  /* Polylines of (xs, ys) split where style(i) changes; style returns
   * {key, dash, width}; each segment gets data-mode = key. */
  function lines(p, xs, ys, keys, color, attrs, style) {
    let start = 0, n = 0;
    for (let i = 1; i <= xs.length; i++) {
      if (i < xs.length && keys[i] === keys[start])
        continue;
      const pts = [];
      for (let k = start; k < i; k++)
        pts.push(p.x(xs[k]).toFixed(2) + "," + p.y(ys[k]).toFixed(2));
      if (pts.length > 1) {
        const s = style(keys[start]);
        el("polyline", Object.assign({
          points: pts.join(" "), fill: "none", stroke: color, "stroke-width": s.width,
          "stroke-dasharray": s.dash, "data-mode": keys[start],
        }, attrs), p.layer);
        n++;
      }
      start = i;
    }
    return n;
  }

  /* A legend: entries {label, color, dash, mark ("line", "box" or "dot"),
   * off}, in the figure's side column when frame() was given one (o.side),
   * else in its top left or right corner (where); toggle(i), when given,
   * is called on a click of entry i (its curves hidden or shown). */
  function legend(p, entries, toggle, where) {
    const g = el("g", { class: "legend", "font-size": 11 }, p.top);
    const width = p.side ? p.side - 10
      : 26 + 6.2 * Math.max(...entries.map((e) => e.label.length));
    const x0 = p.side ? p.pad.left + p.pw + 6
      : where === "left" ? p.pad.left + 6 : p.pad.left + p.pw - width - 6;
    el("rect", { x: x0, y: p.pad.top, width, height: 15 * entries.length + 6,
                 fill: "#fff", "fill-opacity": 0.85, stroke: p.side ? "none" : LINE }, g);
    entries.forEach((e, i) => {
      const y = p.pad.top + 14 + 15 * i;
      const item = el("g", { class: "entry" + (e.off ? " off" : ""), "data-index": i,
                             opacity: e.off ? 0.35 : 1 }, g);
      if (e.mark === "box")
        el("rect", { x: x0 + 4, y: y - 8, width: 12, height: 10, fill: e.color, stroke: LINE }, item);
      else if (e.mark === "dot")
        el("circle", { cx: x0 + 10, cy: y - 3, r: 4, fill: e.color, stroke: e.stroke || "none",
                       "stroke-width": 2 }, item);
      else
        el("line", { x1: x0 + 2, x2: x0 + 18, y1: y - 3, y2: y - 3, stroke: e.color,
                     "stroke-width": 2, "stroke-dasharray": e.dash || "" }, item);
      el("text", { x: x0 + 22, y, fill: INK }, item).textContent = e.label;
      if (toggle) {
        item.setAttribute("cursor", "pointer");
        item.addEventListener("click", (evt) => {
          evt.stopPropagation();
          toggle(i);
        });
      }
    });
    return g;
  }

  /* The data values under the pointer, in the figure's top left corner;
   * more(x, y, evt) adds a line (a cell's orbits, a basin's attractor). */
  function readout(p, more) {
    const g = el("g", { class: "readout", "font-size": 11, visibility: "hidden",
                        "pointer-events": "none" }, p.top);
    const bg = el("rect", { x: p.pad.left + 4, y: p.pad.top + 4, height: 18, fill: "#fff",
                            "fill-opacity": 0.9, stroke: LINE }, g);
    const text = el("text", { x: p.pad.left + 8, y: p.pad.top + 17, fill: INK }, g);
    const move = (evt) => {
      if (!p.inside(evt)) {
        g.setAttribute("visibility", "hidden");
        return;
      }
      const [x, y] = p.invert(evt);
      const extra = more ? more(x, y, evt) : "";
      text.textContent = p.xname + " = " + fmt(x) + ", " + p.yname + " = " + fmt(y) +
        (extra ? "; " + extra : "");
      bg.setAttribute("width", text.getComputedTextLength() + 8);
      g.setAttribute("visibility", "visible");
    };
    p.svg.onmousemove = move;
    p.svg.onmouseleave = () => g.setAttribute("visibility", "hidden");
    return g;
  }

  /* The wheel zooms the figure about the pointer (redraw(xr, yr) draws it
   * over the new ranges); a double click returns to the whole figure. */
  function zoom(p, redraw, whole) {
    p.svg.onwheel = (evt) => {
      if (!p.inside(evt))
        return;
      evt.preventDefault();
      /* by how far the wheel turned: a trackpad sends many small deltas,
       * a mouse's notch (about 100 px) zooms by some 20 % */
      const px = evt.deltaY * (evt.deltaMode === 1 ? 33 : evt.deltaMode === 2 ? 800 : 1);
      const [cx, cy] = p.invert(evt), f = Math.exp(Math.max(-1, Math.min(1, px * 0.002)));
      redraw([cx - (cx - p.xr[0]) * f, cx + (p.xr[1] - cx) * f],
             [cy - (cy - p.yr[0]) * f, cy + (p.yr[1] - cy) * f]);
    };
    p.svg.ondblclick = (evt) => {
      evt.preventDefault();
      redraw(whole[0], whole[1]);
    };
  }

  /* The figure as a standalone SVG document. */
  function svgText(svg) {
    const copy = svg.cloneNode(true);
    copy.setAttribute("xmlns", NS);
    copy.setAttribute("width", svg.dataset.width);
    copy.setAttribute("height", svg.dataset.height);
    copy.removeAttribute("class");
    copy.removeAttribute("style");
    for (const r of copy.querySelectorAll(".readout"))
      r.remove();
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + new XMLSerializer().serializeToString(copy);
  }

  /* The figure as a PNG at twice its size. */
  function pngBlob(svg) {
    return new Promise((resolve, reject) => {
      const img = new Image();
      const k = 2, w = Number(svg.dataset.width), h = Number(svg.dataset.height);
      img.onload = () => {
        const c = document.createElement("canvas");
        c.width = w * k;
        c.height = h * k;
        const g = c.getContext("2d");
        g.scale(k, k);
        g.drawImage(img, 0, 0, w, h);
        c.toBlob((b) => (b ? resolve(b) : reject(new Error("no PNG"))), "image/png");
      };
      img.onerror = () => reject(new Error("the SVG did not render"));
      img.src = "data:image/svg+xml;charset=utf-8," + encodeURIComponent(svgText(svg));
    });
  }

  /* A table {columns, rows} as CSV (RFC 4180 quoting). */
  function csv(table) {
    const q = (v) => {
      const s = v === null || v === undefined ? "" : String(v);
      return /[",\n]/.test(s) ? '"' + s.replace(/"/g, '""') + '"' : s;
    };
    return [table.columns, ...table.rows].map((r) => r.map(q).join(",")).join("\n") + "\n";
  }

  function download(name, blob) {
    const a = document.createElement("a");
    a.href = URL.createObjectURL(blob);
    a.download = name;
    document.body.appendChild(a);
    a.click();
    a.remove();
    setTimeout(() => URL.revokeObjectURL(a.href), 10000);
  }

  return { el, fmt, ticks, extent, inner, frame, lines, legend, readout, zoom, svgText, pngBlob, csv, download };
})();
