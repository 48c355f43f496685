// Bundles the viewer into one minified IIFE script: `node build.mjs OUTFILE`.
// CSS (uPlot's, the viewer's) is imported as text and injected at start-up, so the report page
// needs nothing but this one script.
import * as esbuild from "esbuild";

const outfile = process.argv[2];
if (!outfile) {
  console.error("usage: node build.mjs OUTFILE");
  process.exit(2);
}
await esbuild.build({
  entryPoints: ["src/main.js"],
  bundle: true,
  minify: true,
  format: "iife",
  target: ["es2020"],
  loader: { ".css": "text" },
  legalComments: "none",
  outfile,
  logLevel: "warning",
});
