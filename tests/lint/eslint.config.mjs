// The report page's script: a classic browser script (not a module) after three.js and
// OrbitControls, which define THREE; it keeps everything else on its one global, FF.
import js from "@eslint/js";
import globals from "globals";

export default [
  js.configs.recommended,
  {
    files: ["**/*.js"],
    languageOptions: {
      ecmaVersion: 2020,
      sourceType: "script",
      globals: { ...globals.browser, THREE: "readonly" },
    },
    rules: {
      eqeqeq: "error",
      "no-shadow": "error",
    },
  },
];
