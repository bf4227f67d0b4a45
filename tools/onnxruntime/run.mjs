// Runs ONNX models in ONNX Runtime (CPU) for cgsr: verification of exports and latency.
//
//   node run.mjs JOB.json RESULT.json
//
// JOB.json:    {"threads": N, "models": [{"path": "m.onnx", "runs": [{
//                 "inputs": [{"name": "lr_color", "shape": [1, 3, 10, 12], "file": "in.f32"}],
//                 "output_prefix": "out", "warmup": 0, "repeats": 1}]}]}
// RESULT.json: {"onnxruntime": "1.30.0", "models": [{"path": ..., "load_ms": ..., "error": null,
//                 "runs": [{"outputs": [{"name": "sr", "type": "float32", "shape": [...],
//                                        "file": "out.sr.f32"}], "times_ms": [...]}]}]}
// Tensors are raw little-endian files: inputs float32, outputs of their own type (float32, or
// int64 for an index such as the hybrid selector's ArgMax). An error in one model is recorded in its entry
// and the others still run; the exit code is non-zero only when the job itself is unusable.
import { readFileSync, writeFileSync } from 'node:fs';
import { performance } from 'node:perf_hooks';
import * as ort from 'onnxruntime-node';

function readFloat32(file, shape) {
  const bytes = readFileSync(file);
  const count = shape.reduce((a, b) => a * b, 1);
  if (bytes.byteLength !== count * 4) {
    throw new Error(`${file} holds ${bytes.byteLength} bytes, shape [${shape}] needs ${count * 4}`);
  }
  // Copy into an aligned buffer: a Buffer may start at any byte offset.
  const data = new Float32Array(count);
  new Uint8Array(data.buffer).set(bytes);
  return data;
}

async function runModel(model, threads) {
  const entry = { path: model.path, load_ms: 0, error: null, runs: [] };
  try {
    const start = performance.now();
    const session = await ort.InferenceSession.create(model.path, {
      executionProviders: ['cpu'],
      graphOptimizationLevel: 'all',
      intraOpNumThreads: threads,
      interOpNumThreads: 1,
    });
    entry.load_ms = performance.now() - start;
    for (const run of model.runs) {
      const feeds = {};
      for (const input of run.inputs) {
        feeds[input.name] = new ort.Tensor('float32', readFloat32(input.file, input.shape), input.shape);
      }
      for (let i = 0; i < (run.warmup ?? 0); i++) await session.run(feeds);
      const times = [];
      let results = null;
      for (let i = 0; i < Math.max(1, run.repeats ?? 1); i++) {
        const t0 = performance.now();
        results = await session.run(feeds);
        times.push(performance.now() - t0);
      }
      const outputs = [];
      for (const name of session.outputNames) {
        const tensor = results[name];
        const file = `${run.output_prefix}.${name}.f32`;
        const data = tensor.data;
        writeFileSync(file, Buffer.from(data.buffer, data.byteOffset, data.byteLength));
        outputs.push({ name, type: tensor.type, shape: tensor.dims.map(Number), file });
      }
      entry.runs.push({ outputs, times_ms: times });
    }
  } catch (e) {
    entry.error = String(e && e.message ? e.message : e);
  }
  return entry;
}

const [jobPath, resultPath] = process.argv.slice(2);
if (!jobPath || !resultPath) {
  console.error('usage: node run.mjs JOB.json RESULT.json');
  process.exit(2);
}
const job = JSON.parse(readFileSync(jobPath, 'utf8'));
const threads = Math.max(1, job.threads ?? 1);
const models = [];
for (const model of job.models) models.push(await runModel(model, threads));
writeFileSync(resultPath, JSON.stringify({ onnxruntime: ort.env.versions?.node ?? 'unknown', models }));
