/*
 * Every answer type of the contract, read through the client that
 * openapi-typescript generates from api/openapi.json (check_client.sh writes
 * it to openapi.d.ts beside a copy of this file).  Each declaration names the
 * type a field must have: compiled under tsc --strict, this fails when the
 * contract loses an item type (jacobian: unknown[]), leaves an object empty
 * (input, rejected.margins) or types a batch line's body or an NDJSON line
 * as nothing in particular.  Nothing here runs.
 */
import type { components, paths } from "./openapi";

type S = components["schemas"];
type Json<P extends keyof paths, M extends "get" | "post"> =
  paths[P][M] extends { responses: { 200: { content: { "application/json": infer T } } } }
    ? T : never;

export function orbit(a: Json<"/orbit", "post">): number {
  const o: S["OrbitAnswer"] = a.orbits[0];
  const durations: number[] = o.phases.map((p) => p.duration);
  const mode: "slip" | "overshoot" | "stick" = o.phases[0].mode;
  const z0: number[] = o.z0;
  const m: number | null = o.margins.switching.value;
  const ev: [number, number][] = o.stability.eigenvalues;
  const j: number[][] = o.stability.jacobian;
  const guess: number[] | undefined = a.input.guess?.durations;
  const chi: number | undefined = a.input.params?.chi;
  const omega: number | undefined = a.input.omega;
  const rejected: number[] = a.rejected ? a.rejected.phases.map((p) => p.duration) : [];
  const rm: number | null = a.rejected ? a.rejected.margins.min.value : null;
  return durations[0] + z0[0] + (m ?? 0) + ev[0][1] + j[0][0] + (guess ? guess[0] : 0) +
    (chi ?? 0) + (omega ?? 0) + rejected.length + (rm ?? 0) + mode.length;
}

export function simulate(a: Json<"/simulate", "post">): number {
  const x: number[] = a.final.x;
  const t: number = a.final.t;
  const events: number[] = (a.events ?? []).map((e) => e.t);
  const x1: number[] = a.samples?.x1 ?? [];
  const modes: ("slip" | "overshoot" | "stick")[] = a.samples?.mode ?? [];
  const t_end: number = a.input.t_end;
  return x[0] + t + events.length + x1.length + modes.length + t_end;
}

export function stability(a: Json<"/stability", "post">): number {
  const j: number[][] = a.jacobian;
  const fd: number[][] | undefined = a.jacobian_fd;
  const ev: [number, number][] = a.eigenvalues;
  const marginal: boolean = a.marginal;
  const z0: number[] | undefined = a.input.z0;
  return j[0][0] + (fd ? fd[0][0] : 0) + ev[0][0] + Number(marginal) + (z0 ? z0[0] : 0);
}

export function continuation(a: Json<"/continue", "post">): number {
  const b: S["ContinueBranch"] = a.branches[0];
  const values: (number | undefined)[] = b.points.map((p) => p.value);
  const mult: [number, number][] = b.points[0].multipliers ?? [];
  const special: string[] = b.special.map((s) => s.type);
  const parameter: string = a.input.parameter;
  const range: number[] = a.input.range;
  return values.length + mult.length + special.length + parameter.length + range[0];
}

export function mapLine(line: S["MapLine"] | S["MapDone"]): number {
  if ("done" in line) {
    const cells: number = line.cells;
    const axes: string[] = line.input.axes.map((x) => x.parameter);
    return cells + axes.length;
  }
  const index: number[] = line.index;
  const at: number | undefined = line.at["ur"];
  const mult: [number, number][] = line.orbits[0].multipliers ?? [];
  const marginal: boolean | undefined = line.orbits[0].marginal;
  return index[0] + (at ?? 0) + (mult.length ? mult[0][0] + mult[0][1] : 0) + Number(marginal);
}

export function basins(a: Json<"/basins", "post">): number {
  const at: S["BasinsResponse"]["attractors"][number] = a.attractors[0];
  const phases: number[] = at.phases.map((p) => p.duration);
  const section: number[][] = at.section;
  const data: string = a.labels.data;
  const state: { [key: string]: number } = a.input.state;
  return phases.length + section[0][0] + data.length + Object.keys(state).length;
}

export function batchLine(line: S["BatchLine"] | S["BatchDone"]): number {
  if ("done" in line)
    return line.ok + line.failed;
  const b = line.body;
  if (Array.isArray(b)) {
    const lines: (S["MapLine"] | S["MapDone"])[] = b;
    return lines.map(mapLine).reduce((x, y) => x + y, 0);
  }
  if ("orbits" in b)
    return b.orbits.length;
  if ("final" in b)
    return b.final.t;
  if ("jacobian" in b)
    return b.jacobian[0][0];
  if ("branches" in b)
    return b.branches.length;
  if ("attractors" in b)
    return b.attractors.length;
  const p: S["Problem"] = b;
  return p.status;
}

export function batchItem(i: S["BatchItem"]): number {
  if (i.path === "/simulate")
    return i.body.t_end;
  if (i.path === "/map")
    return i.body.axes.length;
  return 0;
}

export function problem(p: S["Problem"]): string {
  const pointer: string | undefined = p.pointer;
  return p.type + p.title + p.detail + String(p.status) + (pointer ?? "");
}

export function version(a: Json<"/version", "get">): string {
  const v: string = a.version;
  return v + a.gsl + a.jansson + a.microhttpd + a.service;
}

export function health(a: Json<"/health", "get">): number {
  const s: string = a.status;
  return s.length + a.uptime_seconds + a.in_flight;
}
