#!/usr/bin/python3
"""Validates YAML scenes against pdyn's JSON Schema (draft 2020-12).

usage: validate.py SCHEMA --good SCENE... [--bad SCENE...]
Scenes after --good must be accepted, scenes after --bad refused. Exit 0 when
all are as expected, 1 otherwise (each surprise is printed), 2 on bad usage.
"""
import json
import re
import sys

try:
    import jsonschema
    import yaml
except ImportError as e:  # a clear message rather than a traceback
    sys.exit(f"validate.py: {e.name} is missing (install python3-jsonschema and python3-yaml; "
             "scripts/quickstart.sh does)")


class Yaml12Loader(yaml.SafeLoader):
    """PyYAML reads YAML 1.1, where 1e-4 is a string; pdyn (yaml-cpp) and
    yaml-language-server read it as a number, as YAML 1.2 does."""


Yaml12Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                   |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                   |\.[0-9_]+(?:[eE][-+]?[0-9]+)?
                   |[-+]?\.(?:inf|Inf|INF)
                   |\.(?:nan|NaN|NAN))$""", re.X),
    list("-+0123456789."))


def main(argv):
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    with open(argv[1]) as f:
        schema = json.load(f)
    jsonschema.Draft202012Validator.check_schema(schema)
    validator = jsonschema.Draft202012Validator(schema)
    mode, surprises, count = None, 0, 0
    for arg in argv[2:]:
        if arg in ("--good", "--bad"):
            mode = arg
            continue
        if mode is None:
            print(__doc__, file=sys.stderr)
            return 2
        count += 1
        try:
            with open(arg) as f:
                scene = yaml.load(f, Loader=Yaml12Loader)
        except yaml.YAMLError as e:
            if mode == "--good":
                print(f"{arg}: not valid YAML: {str(e).splitlines()[0]}")
                surprises += 1
            continue
        errors = list(validator.iter_errors(scene))
        if mode == "--good" and errors:
            e = jsonschema.exceptions.best_match(errors)
            where = "/".join(str(p) for p in e.absolute_path) or "(top)"
            print(f"{arg}: refused by the schema at {where}: {e.message}")
            surprises += 1
        elif mode == "--bad" and not errors:
            print(f"{arg}: accepted by the schema, but pdyn refuses it")
            surprises += 1
    print(f"validate.py: {count} scenes, {surprises} not as expected")
    return 1 if surprises else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
