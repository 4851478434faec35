#!/usr/bin/env python3
"""Independent checks of proto/ for proto_test.cpp (python3-yaml, python3-jsonschema).

Usage: proto_check.py <proto dir> <out.json>
Writes {"openapi": <the OpenAPI document as JSON>, "examples": [...], "counter_examples": [...]}
after checking that params.schema.json is a valid JSON Schema 2020-12 document, that each of
its "examples" validates and each of its "x-counterExamples" does not. Exits non-zero on failure.

Usage: proto_check.py --reports <proto dir> <document.json>...
Checks report.schema.json the same way, then that every document (a CLI --report, a job's
result) validates against it; exits non-zero naming the first error of each that does not.
"""
import json
import sys

import jsonschema
import yaml


def load_validator(path):
    """The schema at `path` and its validator, once checked to be valid JSON Schema 2020-12."""
    with open(path, encoding="utf-8") as f:
        schema = json.load(f)
    validator_class = jsonschema.validators.validator_for(schema)
    if validator_class is not jsonschema.Draft202012Validator:
        sys.exit(f"{path} must declare draft 2020-12, got {validator_class.__name__}")
    validator_class.check_schema(schema)
    return schema, validator_class(schema)


def check_reports(proto, paths):
    _, validator = load_validator(f"{proto}/report.schema.json")
    failures = []
    for path in paths:
        with open(path, encoding="utf-8") as f:
            document = json.load(f)
        for error in validator.iter_errors(document):
            failures.append(f"{path}: /{'/'.join(str(p) for p in error.absolute_path)}: {error.message}")
            break
    if failures:
        sys.exit("\n".join(failures))


def main():
    if sys.argv[1] == "--reports":
        return check_reports(sys.argv[2], sys.argv[3:])
    proto, out_path = sys.argv[1], sys.argv[2]
    with open(f"{proto}/openapi.yaml", encoding="utf-8") as f:
        openapi = yaml.safe_load(f)
    schema, validator = load_validator(f"{proto}/params.schema.json")
    failures = []
    for example in schema.get("examples", []):
        errors = list(validator.iter_errors(example))
        if errors:
            failures.append(f"example {json.dumps(example)} rejected: {errors[0].message}")
    for counter in schema.get("x-counterExamples", []):
        if validator.is_valid(counter):
            failures.append(f"counter-example {json.dumps(counter)} accepted")
    # Every response of the OpenAPI document that describes an error uses problem+json.
    responses = openapi.get("components", {}).get("responses", {})
    for name, response in responses.items():
        content = response.get("content", {})
        if name not in ("Mesh",) and "application/problem+json" not in content:
            failures.append(f"components.responses.{name} is not application/problem+json")
    if failures:
        sys.exit("\n".join(failures))
    with open(out_path, "w", encoding="utf-8") as f:
        json.dump({"openapi": openapi, "examples": schema.get("examples", []),
                   "counter_examples": schema.get("x-counterExamples", [])}, f)


if __name__ == "__main__":
    main()
