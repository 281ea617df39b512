"""A small, safe arithmetic evaluator for analytic reference values written in sweep files.

    exact = "P * L**3 / (3 * E * I)"
    constants = { P = -100.0, L = 1.0, E = 2.1e11, I = "b * t**3 / 12", b = 1.0 }
    bind = { t = "structure.section.thickness" }     # taken from the run's overrides

Only numbers, names, + - * / ** %, unary +/-, parentheses and the functions below are allowed; names
resolve first from `bind` (the run's override values), then from `constants` (which may themselves be
formulas, evaluated on demand; cycles are reported), then from the built-in constants pi and e.
"""
import ast
import math

FUNCTIONS = {
    "sqrt": math.sqrt, "exp": math.exp, "log": math.log, "log10": math.log10, "sin": math.sin, "cos": math.cos,
    "tan": math.tan, "atan": math.atan, "abs": abs, "min": min, "max": max, "cosh": math.cosh, "sinh": math.sinh,
    "tanh": math.tanh,
}
BUILTIN_CONSTANTS = {"pi": math.pi, "e": math.e}


class FormulaError(ValueError):
    pass


def evaluate(expr, constants=None, bound=None):
    """Value of `expr` (a number or a formula string) with the given names."""
    constants = dict(constants or {})
    bound = dict(bound or {})
    cache = {}

    def name_value(name, stack):
        if name in bound:
            return _number(bound[name], f"bound name {name!r}")
        if name in cache:
            return cache[name]
        if name in constants:
            if name in stack:
                raise FormulaError(f"constants refer to each other in a cycle: {' -> '.join(stack + [name])}")
            v = value_of(constants[name], stack + [name])
            cache[name] = v
            return v
        if name in BUILTIN_CONSTANTS:
            return BUILTIN_CONSTANTS[name]
        raise FormulaError(f"unknown name {name!r} (give it in constants or bind)")

    def value_of(x, stack):
        if isinstance(x, bool):
            raise FormulaError(f"expected a number or a formula, got {x!r}")
        if isinstance(x, (int, float)):
            return float(x)
        if not isinstance(x, str):
            raise FormulaError(f"expected a number or a formula, got {x!r}")
        try:
            tree = ast.parse(x, mode="eval")
        except SyntaxError as err:
            raise FormulaError(f"cannot parse formula {x!r}: {err.msg}") from None
        return ev(tree.body, stack, x)

    def ev(node, stack, text):
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
            return float(node.value)
        if isinstance(node, ast.Name):
            return name_value(node.id, stack)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.UAdd, ast.USub)):
            v = ev(node.operand, stack, text)
            return v if isinstance(node.op, ast.UAdd) else -v
        if isinstance(node, ast.BinOp):
            a, b = ev(node.left, stack, text), ev(node.right, stack, text)
            ops = {ast.Add: lambda: a + b, ast.Sub: lambda: a - b, ast.Mult: lambda: a * b, ast.Div: lambda: a / b,
                   ast.Pow: lambda: a ** b, ast.Mod: lambda: a % b}
            for kind, f in ops.items():
                if isinstance(node.op, kind):
                    try:
                        value = f()
                        if isinstance(value, complex):  # a negative number to a fractional power
                            raise FormulaError(f"in {text!r}: {a!r} ** {b!r} is not a real number")
                        return float(value)
                    except (ZeroDivisionError, OverflowError) as err:
                        raise FormulaError(f"in {text!r}: {err}") from None
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS \
                and not node.keywords:
            args = [ev(a, stack, text) for a in node.args]
            try:
                return float(FUNCTIONS[node.func.id](*args))
            except (ValueError, TypeError, OverflowError) as err:
                raise FormulaError(f"in {text!r}: {node.func.id}: {err}") from None
        raise FormulaError(f"in {text!r}: only numbers, names, + - * / ** %, parentheses and "
                           f"{', '.join(sorted(FUNCTIONS))} are allowed")

    return value_of(expr, [])


def _number(v, what):
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        raise FormulaError(f"{what} is {v!r}, not a number")
    return float(v)


def exact_value(params, settings, key="exact"):
    """The analytic value `params[key]` of a metric: a number or a formula with params['constants'] and
    params['bind'] (name -> scene key whose value is taken from the run's overrides)."""
    if key not in params:
        raise FormulaError(f"missing parameter {key!r}")
    bound = {}
    for name, scene_key in (params.get("bind") or {}).items():
        if scene_key not in settings:
            raise FormulaError(f"bind: {name} = {scene_key!r}, but this run does not override {scene_key!r} "
                               "(only overridden keys can be bound; add it to [fixed])")
        bound[name] = settings[scene_key]
    return evaluate(params[key], params.get("constants"), bound)
