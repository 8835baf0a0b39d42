/**
 * FreeSewing measurement sets (mm) for the 12 sizes (00..20) of the ASTM
 * D5585-11 misses chart that grade3d's benchmark grades
 * (fixtures/size-charts/astm-d5585-11-misses-partial.csv, inches).
 *
 * The measurements each design requires were read from the designs
 * themselves (`new Titan().getConfig().measurements`, FreeSewing 4.10.2;
 * neither design has optional measurements), and are checked again at run
 * time by draft.mjs:
 *   titan: crossSeam crossSeamFront knee seat seatBack waist waistBack
 *          waistToFloor waistToKnee waistToHips waistToSeat waistToUpperLeg
 *   bella: highBust chest underbust waist waistBack bustSpan neck hpsToBust
 *          hpsToWaistFront hpsToWaistBack shoulderToShoulder shoulderSlope
 *          biceps shoulderToWrist waistToArmpit wrist
 *          (the last four come from its sleeve part, via @freesewing/library)
 *
 * From the chart (inches x 25.4 = mm, unrounded):
 *   FreeSewing   chart column          used by
 *   waist        waist_girth_curvy     titan, bella  (curvy is grade3d's default
 *                                                     figure type for this chart)
 *   chest        bust_girth            bella  (FreeSewing's chest = full bust girth)
 *   highBust     upper_chest_girth     bella
 *   underbust    underbust_girth       bella
 *   neck         neck_base_girth       bella
 * Not used: shoulder_girth (FreeSewing has no shoulder girth; its
 * shoulderToShoulder is an across-back length), waist_girth_straight.
 *
 * Derived (everything else each design requires): from ONE published FreeSewing
 * sample body, cisFemaleAdult34 of @freesewing/models 4.10.2 (neck 340 mm; it is
 * the unextrapolated base "average woman" of FreeSewing's models, chest 925 mm,
 * waist 750 mm), scaled linearly by one ratio per size and design:
 *   titan: r = chart waist / 750     -> crossSeam crossSeamFront knee seat seatBack
 *          waistBack waistToFloor waistToKnee waistToHips waistToSeat waistToUpperLeg
 *   bella: r = chart bust / 925      -> bustSpan hpsToBust hpsToWaistFront
 *          hpsToWaistBack shoulderToShoulder biceps shoulderToWrist waistToArmpit wrist
 *   except, for bella:
 *     waistBack     = 380 * chart waist / 750 (the waist ratio, as for titan: it is
 *                     the back part of the chart's waist, and this keeps the sample's
 *                     back/front split, waistBack = 1.013 x waist/2, in every size;
 *                     scaled by the bust ratio it would drift from 1.07 x waist/2 in
 *                     size 00 to 0.97 x in size 20)
 *     shoulderSlope = 13 (degrees: an angle, not scaled; FreeSewing's own models
 *                     do not scale degree measurements either)
 * Lengths are scaled by the same girth ratio (a plain proportional body; the
 * chart has no lengths). The derived sets are a benchmark workload, not a fit
 * claim.
 */
import { readFileSync } from 'node:fs'
import { fileURLToPath } from 'node:url'
import { cisFemaleAdult34 } from '@freesewing/models'

export const CHART_PATH = fileURLToPath(
  new URL('../../../fixtures/size-charts/astm-d5585-11-misses-partial.csv', import.meta.url)
)

export const SAMPLE_NAME = 'cisFemaleAdult34 (@freesewing/models 4.10.2)'
export const SAMPLE = cisFemaleAdult34

const MM_PER_IN = 25.4

/** FreeSewing measurement <- chart column, per design */
export const FROM_CHART = {
  titan: { waist: 'waist_girth_curvy' },
  bella: {
    waist: 'waist_girth_curvy',
    chest: 'bust_girth',
    highBust: 'upper_chest_girth',
    underbust: 'underbust_girth',
    neck: 'neck_base_girth',
  },
}

/** Derived measurements: [FreeSewing name, which chart-to-sample ratio scales it] */
export const DERIVED = {
  titan: [
    'crossSeam',
    'crossSeamFront',
    'knee',
    'seat',
    'seatBack',
    'waistBack',
    'waistToFloor',
    'waistToKnee',
    'waistToHips',
    'waistToSeat',
    'waistToUpperLeg',
  ].map((m) => [m, 'waist']),
  bella: [
    ...[
      'bustSpan',
      'hpsToBust',
      'hpsToWaistFront',
      'hpsToWaistBack',
      'shoulderToShoulder',
      'biceps',
      'shoulderToWrist',
      'waistToArmpit',
      'wrist',
    ].map((m) => [m, 'bust']),
    ['waistBack', 'waist'],
    ['shoulderSlope', 'none'],
  ],
}

/** Parses the chart: [{ size, unit, <column>: inches, ... }] in chart order */
export function readChart(path = CHART_PATH) {
  const lines = readFileSync(path, 'utf8')
    .split(/\r?\n/)
    .map((l) => l.trim())
    .filter((l) => l && !l.startsWith('#'))
  const header = lines[0].split(',')
  return lines.slice(1).map((line) => {
    const cells = line.split(',')
    const row = {}
    header.forEach((h, i) => {
      row[h] = h === 'size' || h === 'unit' ? cells[i] : Number(cells[i])
    })
    if (row.unit !== 'in') throw new Error(`size ${row.size}: expected unit "in", got ${row.unit}`)
    return row
  })
}

/**
 * The measurement sets of one design for every size of the chart:
 * [{ size: '00', measurements: { ... mm } }, ...]
 */
export function measurementSets(design, chart = readChart()) {
  if (!FROM_CHART[design]) throw new Error(`unknown design ${design}`)
  return chart.map((row) => {
    const mm = (col) => {
      const v = row[col]
      if (!Number.isFinite(v)) throw new Error(`size ${row.size}: no ${col} in the chart`)
      return v * MM_PER_IN
    }
    const ratio = {
      waist: mm('waist_girth_curvy') / SAMPLE.waist,
      bust: mm('bust_girth') / SAMPLE.chest,
      none: 1,
    }
    const measurements = {}
    for (const [m, col] of Object.entries(FROM_CHART[design])) measurements[m] = mm(col)
    for (const [m, by] of DERIVED[design]) measurements[m] = SAMPLE[m] * ratio[by]
    return { size: row.size, measurements }
  })
}

// `node measurements.mjs [titan|bella]` prints the sets (mm, 1 decimal) as JSON
if (process.argv[1] && fileURLToPath(import.meta.url) === process.argv[1]) {
  const designs = process.argv[2] ? [process.argv[2]] : ['titan', 'bella']
  for (const d of designs) {
    const sets = measurementSets(d).map(({ size, measurements }) => ({
      size,
      measurements: Object.fromEntries(
        Object.entries(measurements).map(([k, v]) => [k, Math.round(v * 10) / 10])
      ),
    }))
    console.log(JSON.stringify({ design: d, sample: SAMPLE_NAME, sets }, null, 1))
  }
}
