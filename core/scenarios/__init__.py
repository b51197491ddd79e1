"""Built-in scenario files (TOML): the paper's examples, the smoke scenario and the real-data
example in ``scenarios/``, built-in studies in ``scenarios/studies/``. Data only, no code."""
