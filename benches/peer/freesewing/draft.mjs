#!/usr/bin/env node
/**
 * Peer benchmark for grade3d issue #15: FreeSewing v4 drafts a design for the
 * 12 sizes of the ASTM D5585 misses chart and renders each to an SVG string.
 *
 *   node draft.mjs [--runs N] [--design titan|bella|both] [--out DIR]
 *
 * One run = for each of the 12 sizes: new Design({ measurements }) with default
 * options, .draft(), .render(). The wall time of a run (performance.now()) covers
 * those 12 sizes only; module loading and the measurement sets are prepared
 * before. After each run (outside the timing) every size is checked: no error in
 * the pattern's or its set's store logs, every part drafted with at least one
 * path, and a non-empty <svg> with <path> elements. Any failure is printed to
 * stderr and the exit status is 1. Warnings are printed to stderr, not fatal.
 *
 * stdout: one JSON line per design,
 *   {"design":"titan","sizes":12,"runs":N,"first_ms":..,"min_ms":..,"median_ms":..,"max_ms":..}
 * first_ms is run 1 (cold JIT); min/median/max are over runs 2..N (warm), or
 * over run 1 alone when N = 1. With --design both, titan runs first, so bella's
 * first run starts with core's code already warm.
 * --out DIR writes DIR/<design>-<size>.svg from the last run.
 */
import { mkdirSync, writeFileSync } from 'node:fs'
import { join } from 'node:path'
import { performance } from 'node:perf_hooks'
import { Titan } from '@freesewing/titan'
import { Bella } from '@freesewing/bella'
import { measurementSets } from './measurements.mjs'

const DESIGNS = { titan: Titan, bella: Bella }

function usage(msg) {
  if (msg) console.error(`draft.mjs: ${msg}`)
  console.error('usage: node draft.mjs [--runs N] [--design titan|bella|both] [--out DIR]')
  process.exit(2)
}

function parseArgs(argv) {
  const args = { runs: 5, design: 'both', out: null }
  for (let i = 0; i < argv.length; i++) {
    const a = argv[i]
    const val = () => {
      if (i + 1 >= argv.length) usage(`${a} needs a value`)
      return argv[++i]
    }
    if (a === '--runs') args.runs = Number(val())
    else if (a === '--design') args.design = val()
    else if (a === '--out') args.out = val()
    else if (a === '-h' || a === '--help') usage()
    else usage(`unknown argument ${a}`)
  }
  if (!Number.isInteger(args.runs) || args.runs < 1) usage('--runs must be a positive integer')
  if (args.design !== 'both' && !DESIGNS[args.design]) usage(`unknown design ${args.design}`)
  return args
}

/** A log entry as text (core logs strings, or [message, Error] for a part that threw) */
const logText = (e) =>
  Array.isArray(e)
    ? e.map(logText).join(': ')
    : e instanceof Error
      ? e.stack || String(e)
      : typeof e === 'string'
        ? e
        : JSON.stringify(e)

/** Problems of one drafted and rendered size, [] when it is fine */
function check(design, size, pattern, svg) {
  const problems = []
  const logs = pattern.getLogs()
  for (const [where, l] of [['pattern', logs.pattern], ...logs.sets.map((l, i) => [`set ${i}`, l])]) {
    for (const e of l.error) problems.push(`error (${where}): ${logText(e)}`)
    for (const w of l.warn) console.error(`${design} ${size}: warning (${where}): ${logText(w)}`)
  }
  const parts = pattern.parts?.[0] ?? {}
  if (Object.keys(parts).length === 0) problems.push('no part drafted')
  for (const [name, part] of Object.entries(parts)) {
    if (Object.keys(part.paths ?? {}).length === 0) problems.push(`part ${name} has no path`)
  }
  if (typeof svg !== 'string' || svg.length === 0) problems.push('empty SVG')
  else if (!svg.includes('<svg') || !svg.includes('<path')) problems.push('SVG without <svg>/<path>')
  return problems.map((p) => `${design} size ${size}: ${p}`)
}

const median = (xs) => {
  const s = [...xs].sort((a, b) => a - b)
  const m = s.length >> 1
  return s.length % 2 ? s[m] : (s[m - 1] + s[m]) / 2
}
const r3 = (x) => Math.round(x * 1000) / 1000

function bench(design, runs, out) {
  const Design = DESIGNS[design]
  const sets = measurementSets(design)
  // every measurement the design requires must be in every set
  const config = new Design().getConfig()
  const required = [...(config.measurements ?? []), ...(config.optionalMeasurements ?? [])]
  for (const { size, measurements } of sets) {
    const missing = required.filter((m) => !Number.isFinite(measurements[m]))
    if (missing.length) {
      console.error(`${design} size ${size}: missing measurements ${missing.join(', ')}`)
      process.exit(1)
    }
  }

  const times = []
  let last = null
  for (let run = 0; run < runs; run++) {
    const results = new Array(sets.length)
    const t0 = performance.now()
    for (let i = 0; i < sets.length; i++) {
      const pattern = new Design({ measurements: sets[i].measurements })
      pattern.draft()
      results[i] = { pattern, svg: pattern.render() }
    }
    times.push(performance.now() - t0)

    const problems = results.flatMap((r, i) => check(design, sets[i].size, r.pattern, r.svg))
    if (problems.length) {
      for (const p of problems) console.error(p)
      process.exit(1)
    }
    last = results
  }

  if (out) {
    mkdirSync(out, { recursive: true })
    last.forEach((r, i) => writeFileSync(join(out, `${design}-${sets[i].size}.svg`), r.svg))
  }

  const warm = runs > 1 ? times.slice(1) : times
  return {
    design,
    sizes: sets.length,
    runs,
    first_ms: r3(times[0]),
    min_ms: r3(Math.min(...warm)),
    median_ms: r3(median(warm)),
    max_ms: r3(Math.max(...warm)),
  }
}

const args = parseArgs(process.argv.slice(2))
const designs = args.design === 'both' ? ['titan', 'bella'] : [args.design]
for (const d of designs) console.log(JSON.stringify(bench(d, args.runs, args.out)))
