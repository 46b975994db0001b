"""Safe parsing of expressions from untrusted text.

Scene files carry the Lagrangian and the constraints as strings. They are
never evaluated as Python: :func:`parse_expression` parses the text with
:func:`ast.parse` and builds the sympy expression by walking the syntax tree
with a strict whitelist (numbers, names from an explicit symbol table, the
functions in :data:`FUNCTIONS`, ``pi``, ``+ - * / **`` and unary signs).
Anything else is a :class:`~nhham.errors.ParseError` whose message starts
with the key path it came from and quotes the offending fragment.

Names are ordinary symbols: ``I``, ``E``, ``S``, ``N``, ``beta``, ``gamma``,
``lambda`` mean whatever the symbol table says, never sympy's imaginary unit,
Euler's number and so on. Names are read exactly as written: text that is not
in Unicode normal form NFKC (a full-width ``ｍ``, a mathematical italic ``𝑚``,
which Python would silently read as ``m``) is refused.

Data are real: a constant that is not a real number (``sqrt(-1)``, ``log(-1)``,
``asin(2)``) and a literal outside double precision's range (``1e-400``, which
Python reads as 0) are refused, never truncated;
:func:`nhham.system.numbers.number_problems` applies the same rules to
expressions built with sympy.

The work done on hostile input is bounded: the text length, the nesting
depth, the size of exact numbers and numeric powers are all capped, and every
failure of the Python parser itself is reported as a ``ParseError``.

:func:`to_text` is the inverse (:mod:`nhham.system.printing`, re-exported here): it
prints an expression in the scene's own names so that :func:`parse_expression` reads it
back to an equal expression.
"""

from __future__ import annotations

import ast
import difflib
import io
import keyword
import math
import tokenize
import unicodedata
import warnings
from typing import Iterable, Mapping

import sympy as sp

from nhham.errors import BudgetExceeded, ParseError
from nhham.settings import COMPILER_LOCK
from nhham.system.derivative import derivative
from nhham.system.numbers import complex_string, number_problems
from nhham.system.printing import short, to_text

__all__ = [
    "FUNCTIONS",
    "CONSTANTS",
    "RESERVED_NAMES",
    "MAX_EXPRESSION_LENGTH",
    "CHARACTERS_PER_NAME",
    "expression_limit",
    "parse_expression",
    "to_text",
    "short",
    "derivative",
]

#: Functions an expression may call: name -> (sympy function, allowed arities).
FUNCTIONS: Mapping[str, object] = {
    "sin": sp.sin,
    "cos": sp.cos,
    "tan": sp.tan,
    "exp": sp.exp,
    "log": sp.log,
    "sqrt": sp.sqrt,
    "sinh": sp.sinh,
    "cosh": sp.cosh,
    "tanh": sp.tanh,
    "asin": sp.asin,
    "acos": sp.acos,
    "atan": sp.atan,
    "atan2": sp.atan2,
    "Abs": sp.Abs,
    "sign": sp.sign,
}

#: Number of positional arguments each function takes.
_ARITY: Mapping[str, int] = {name: 1 for name in FUNCTIONS} | {"atan2": 2}

#: Named constants an expression may use.
CONSTANTS: Mapping[str, sp.Expr] = {"pi": sp.pi}

#: Names a symbol table should not use: functions, constants and the Python
#: literals ``True``/``False``/``None`` (which the parser never sees as names).
RESERVED_NAMES = frozenset(FUNCTIONS) | frozenset(CONSTANTS) | {"True", "False", "None"}

#: Longest expression text accepted (characters) whatever the model: a bound on hostile
#: input. A model's own expressions grow with its names (the 64-link snake's Lagrangian:
#: 128,739 characters over 260 names), so the bound is this or :data:`CHARACTERS_PER_NAME`
#: times the names an expression may use, whichever is larger; ``NHHAM_MAX_EXPRESSION``
#: (characters) raises it further. Parsing stays linear in the text, and the other bounds
#: (nesting, numbers, expansion) hold at any length.
MAX_EXPRESSION_LENGTH = 100_000
CHARACTERS_PER_NAME = 2_000

# Deepest nesting of sub-expressions the tree walker follows. Sums, products
# and sign chains are flattened iteratively, so only genuinely nested input
# (parentheses, calls, towers of powers) counts; Python's own tokenizer stops
# at 200 nested parentheses already.
_MAX_DEPTH = 200

# Largest numeric exponent accepted, and the largest exact number (in bits)
# that a sum, product or power may produce: bounded memory and time on input
# such as 10**10**10 or 9**999*9**999*... .
_MAX_EXPONENT = 1000
_MAX_NUMBER_BITS = 100_000
# sympy factors exact numbers to simplify their roots (sqrt(n), n**(1/3));
# beyond this size that takes seconds to minutes.
_MAX_ROOT_BITS = 256

# Longest fragment quoted in an error message.
_QUOTE_LIMIT = 60

_NONFINITE = (sp.zoo, sp.nan, sp.oo, -sp.oo)


# --------------------------------------------------------------------- parse
def parse_expression(text: str, symbols: Mapping[str, sp.Symbol] | Iterable,
                     where: str = "expression") -> sp.Expr:
    """Parse untrusted text into a sympy expression without evaluating Python.

    This is how to read back any expression nhham prints (scene files, the
    JSON of the ``nhham`` command, :func:`to_text`): with the names it may
    use, a parameter called ``I`` is a real symbol, not sympy's imaginary unit.

    Parameters
    ----------
    text : str
        The expression, in Python syntax restricted to numbers, names,
        ``+ - * / **``, unary signs and calls of :data:`FUNCTIONS`. Line
        breaks count as spaces, so a long expression may span several lines.
    symbols : mapping of str to sympy.Symbol, or iterable of str or sympy.Symbol
        The symbol table: every name the expression may use besides the
        functions and ``pi`` (a list of names makes plain real-unassumed
        symbols; Symbols keep their assumptions). Python keywords (``lambda``)
        may be table names. The ``nhham`` command's JSON lists them in
        ``scene.names``.
    where : str, optional
        Key path of the text (``constraints[1]``); every error message
        starts with it.

    Returns
    -------
    sympy.Expr
        The expression. Integer literals stay exact, ``1/2`` is
        ``Rational(1, 2)``, float literals become :class:`sympy.Float`.

    Raises
    ------
    ParseError
        On a syntax error, a construct outside the whitelist, an unknown name
        (with the closest known name suggested; the name is the error's
        ``unknown_name``), a wrong number of function arguments, a division by
        zero, a number that is not real or not a double, text not in Unicode
        normal form NFKC, or input too large or too deeply nested to handle in
        bounded time and memory. Its ``key`` is ``where``.

    Examples
    --------
    >>> from nhham import parse_expression
    >>> energy = parse_expression("I*theta_dot**2/2", ["theta", "theta_dot", "I"])
    >>> energy, sorted(map(str, energy.free_symbols))    # I is a name, not sqrt(-1)
    (I*theta_dot**2/2, ['I', 'theta_dot'])
    """
    try:
        return _parse(text, symbols, where)
    except ParseError as exc:
        if exc.key is None:
            exc.key = where
        raise


def expression_limit(names: int) -> int:
    """The longest expression text accepted over a table of ``names`` names (see
    :data:`MAX_EXPRESSION_LENGTH`).

    >>> expression_limit(4), expression_limit(260)
    (100000, 520000)
    """
    import os

    limit = max(MAX_EXPRESSION_LENGTH, CHARACTERS_PER_NAME * names)
    raised = os.environ.get("NHHAM_MAX_EXPRESSION", "")
    return max(limit, int(raised)) if raised.strip().isdigit() else limit


def _parse(text, symbols, where) -> sp.Expr:
    if not isinstance(text, str):
        raise ParseError(f"{where}: expected an expression string, got {type(text).__name__}")
    symbols = _symbol_table(symbols)
    limit = expression_limit(len(symbols))
    if len(text) > limit:
        raise ParseError(
            f"{where}: expression too long ({len(text)} characters; at most {limit} are "
            f"accepted for {len(symbols)} names; NHHAM_MAX_EXPRESSION=CHARACTERS raises it)"
        )
    if "#" in text:
        # Comments would silently swallow the rest of a multi-line expression.
        raise ParseError(f"{where}: '#' is not allowed in an expression "
                         f"({_position(text, text.index('#'))})")
    # Line breaks become spaces (same length, so positions stay valid);
    # leading blanks would otherwise be an "unexpected indent".
    flat = text.replace("\r", " ").replace("\n", " ")
    body = flat.lstrip()
    lead = len(flat) - len(body)
    if not body.strip():
        raise ParseError(f"{where}: empty expression")
    if not unicodedata.is_normalized("NFKC", body):
        raise ParseError(f"{where}: {_not_normalized(body, lead, text)}")
    source, renamed = _rename_keywords(body, symbols, where)
    tree = _ast_parse(source, text, lead, where)
    builder = _Builder(body, symbols, renamed, where)
    expr = builder.build(tree.body)
    if expr.has(*_NONFINITE):
        raise ParseError(f"{where}: the expression is not finite ({_quote(body)} gives {expr})")
    problems = number_problems(expr)
    if problems:
        raise ParseError(f"{where}: {problems[0]}")
    return _real_parts(expr)


def _real_parts(expr):
    """``expr`` with re(s) -> s and im(s) -> 0 for its symbols, which are all real.

    sympy's symbols carry no assumption, so it evaluates Abs(exp(x)) to exp(re(x)),
    which no scene can write back; every symbol of a scene is real (coordinates,
    velocities, parameters, inputs, t), so the two are the same function.
    """
    if not expr.has(sp.re, sp.im):
        return expr
    return expr.replace(lambda e: isinstance(e, (sp.re, sp.im)) and e.args[0].is_Symbol,
                        lambda e: e.args[0] if isinstance(e, sp.re) else sp.S.Zero)


def _not_normalized(body: str, lead: int, text: str) -> str:
    """Describe the first character (or pair) of ``body`` that NFKC would change."""
    for width in (1, 2):
        for i in range(len(body) - width + 1):
            piece = body[i:i + width]
            normal = unicodedata.normalize("NFKC", piece)
            if normal != piece:
                names = ", ".join(f"U+{ord(c):04X} {unicodedata.name(c, '?')}" for c in piece)
                return (f"{piece!r} ({names}) {_position(text, lead + i)} is not in Unicode "
                        f"normal form NFKC (normalised, as Python reads names, it becomes {normal!r}); "
                        f"write names exactly as they are declared")
    return "the text is not in Unicode normal form NFKC; write names as they are declared"


def _symbol_table(symbols) -> Mapping[str, sp.Symbol]:
    """A name -> Symbol table from a mapping or an iterable of names/Symbols."""
    if isinstance(symbols, Mapping):
        return symbols
    table: dict[str, sp.Symbol] = {}
    for item in symbols:
        sym = item if isinstance(item, sp.Symbol) else sp.Symbol(str(item))
        table[sym.name] = sym
    return table


def _ast_parse(source: str, original: str, lead: int, where: str) -> ast.Expression:
    """Run :func:`ast.parse`, turning each of its failures into a ParseError."""
    try:
        with COMPILER_LOCK, warnings.catch_warnings():
            # Input such as "'\\d'" or "1 is 1" makes the compiler warn on
            # stderr; the expression is refused later anyway.
            warnings.simplefilter("ignore")
            return ast.parse(source, mode="eval")
    except SyntaxError as exc:
        # Single line after flattening: offset is a 1-based character column.
        offset = lead + max((exc.offset or 1) - 1, 0)
        raise ParseError(
            f"{where}: syntax error {_position(original, offset)}: {exc.msg}"
        ) from None
    except (RecursionError, MemoryError):
        # The parser's own limits: deep nesting, or a flat sum of several
        # thousand terms (Python builds it as a deeply nested tree).
        raise ParseError(f"{where}: expression too deeply nested or too many terms "
                         f"in one sum to parse") from None
    except ValueError as exc:  # e.g. integer literal with too many digits
        raise ParseError(f"{where}: cannot parse: {exc}") from None


def _position(text: str, offset: int) -> str:
    """Describe a 0-based character offset as ``at column N`` (1-based)."""
    offset = min(max(offset, 0), len(text))
    line = text.count("\n", 0, offset) + 1
    column = offset - (text.rfind("\n", 0, offset) + 1) + 1
    if "\n" in text:
        return f"at line {line}, column {column}"
    return f"at column {column}"


def _rename_keywords(text: str, symbols: Mapping[str, sp.Symbol], where: str) -> tuple[str, dict]:
    """Replace table names that are Python keywords by same-length placeholders.

    ``lambda`` is a natural parameter name but ``ast.parse`` cannot read it
    as a name. Each keyword that is also a table name is replaced, token by
    token, with an identifier of the same length that occurs nowhere else, so
    every column offset stays valid for error messages.

    Returns
    -------
    text : str
        The text to give to ``ast.parse``.
    renamed : dict
        Placeholder -> original table name.
    """
    wanted = {name for name in symbols if keyword.iskeyword(name)}
    if not wanted or not any(name in text for name in wanted):
        return text, {}
    try:
        tokens = list(tokenize.generate_tokens(io.StringIO(text).readline))
    except (tokenize.TokenError, SyntaxError, RecursionError, MemoryError):
        return text, {}  # ast.parse will report the syntax error properly
    used = {tok.string for tok in tokens if tok.type == tokenize.NAME}
    placeholders: dict[str, str] = {}
    chars = list(text)
    for tok in tokens:
        if tok.type != tokenize.NAME or tok.string not in wanted:
            continue
        if tok.string not in placeholders:
            taken = used | set(symbols) | set(FUNCTIONS) | set(CONSTANTS) | set(placeholders.values())
            placeholders[tok.string] = _placeholder(tok.string, taken, where)
        start = tok.start[1]  # text is a single line
        chars[start:start + len(tok.string)] = placeholders[tok.string]
    return "".join(chars), {new: old for old, new in placeholders.items()}


def _placeholder(word: str, taken: set, where: str) -> str:
    """An identifier as long as ``word`` that is not a keyword nor in ``taken``."""
    alphabet = "abcdefghijklmnopqrstuvwxyz0123456789"
    n = len(word)
    for first in "_ZQXJK":
        for i in range(len(alphabet) ** min(n - 1, 2)):
            tail = ""
            j = i
            for _ in range(min(n - 1, 2)):
                tail += alphabet[j % len(alphabet)]
                j //= len(alphabet)
            candidate = (first + tail + "_" * n)[:n]
            if candidate.isidentifier() and not keyword.iskeyword(candidate) \
                    and candidate not in taken and not candidate.startswith("__"):
                return candidate
    raise ParseError(f"{where}: too many names to rename the keyword name {word!r}")


# ------------------------------------------------------------------ builder
class _Builder:
    """Turn a whitelisted Python AST into a sympy expression.

    Parameters
    ----------
    text : str
        The text the AST positions refer to (for quoting fragments).
    symbols : mapping
        The symbol table.
    renamed : dict
        Placeholder -> table name for keyword names (see _rename_keywords).
    where : str
        Key path prefix for error messages.
    """

    def __init__(self, text, symbols, renamed, where):
        self.text = text
        self.symbols = symbols
        self.renamed = renamed
        self.where = where
        self.calls: dict = {}   # (function, arguments) -> value: a snake's L repeats them

    # Errors ---------------------------------------------------------------
    def fragment(self, node) -> str:
        """The source text of ``node``, quoted and shortened for messages."""
        try:
            segment = ast.get_source_segment(self.text, node)
        except BudgetExceeded:
            raise
        except Exception:  # positions missing or odd: quote nothing rather than fail
            segment = None
        return _quote(segment if segment else type(node).__name__)

    def error(self, node, message: str) -> ParseError:
        return ParseError(f"{self.where}: {message} in {self.fragment(node)}")

    # Dispatch -------------------------------------------------------------
    def build(self, node, depth: int = 0) -> sp.Expr:
        if depth > _MAX_DEPTH:
            raise ParseError(f"{self.where}: expression nested too deeply "
                             f"(more than {_MAX_DEPTH} levels)")
        handler = self._HANDLERS.get(type(node))
        if handler is None:
            raise self.error(node, f"{_describe(node)} is not allowed")
        try:
            return handler(self, node, depth)
        except RecursionError:
            # sympy itself may recurse on deep input; report, do not crash.
            raise ParseError(f"{self.where}: expression nested too deeply") from None

    def constant(self, node, depth):
        value = node.value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise self.error(node, f"{_describe(node)} is not allowed (only real numbers)")
        if isinstance(value, int):
            return sp.Integer(value)
        if not math.isfinite(value):
            raise self.error(node, "number out of range")
        if value == 0.0 and any(c in "123456789" for c in self.mantissa(node)):
            raise ParseError(f"{self.where}: the number {self.fragment(node)} is outside the range "
                             f"of double precision (about 1e-308 to 1e308; it would be read as 0)")
        return sp.Float(value)

    def mantissa(self, node) -> str:
        """The digits of a float literal before its exponent."""
        segment = ast.get_source_segment(self.text, node) or ""
        return segment.lower().split("e")[0]

    def name(self, node, depth):
        ident = self.renamed.get(node.id, node.id)
        if ident.startswith("__"):
            raise self.error(node, f"name {ident!r} is not allowed")
        if ident in self.symbols:
            return self.symbols[ident]
        if ident in CONSTANTS:
            return CONSTANTS[ident]
        if ident in FUNCTIONS:
            raise self.error(node, f"{ident!r} is a function; call it as {ident}(...)")
        error = ParseError(f"{self.where}: unknown name {ident!r}{self.suggest(ident)}")
        error.unknown_name = ident  # a scene adds where to declare it
        raise error

    def suggest(self, ident: str) -> str:
        known = list(self.symbols) + list(CONSTANTS) + list(FUNCTIONS)
        close = difflib.get_close_matches(ident, known, n=1)
        return f"; did you mean {close[0]!r}?" if close else ""

    def unary(self, node, depth):
        # Sign chains (- - - x) are counted iteratively, not recursed into.
        negative = False
        while isinstance(node, ast.UnaryOp):
            if isinstance(node.op, ast.USub):
                negative = not negative
            elif not isinstance(node.op, ast.UAdd):
                raise self.error(node, f"operator {_describe(node.op)} is not allowed")
            node = node.operand
        value = self.build(node, depth + 1)
        return -value if negative else value

    def binop(self, node, depth):
        if isinstance(node.op, (ast.Add, ast.Sub)):
            return self.sum_chain(node, depth)
        if isinstance(node.op, (ast.Mult, ast.Div)):
            return self.product_chain(node, depth)
        if isinstance(node.op, ast.Pow):
            return self.power(node, depth)
        raise self.error(node, f"operator {_describe(node.op)} is not allowed")

    def chain(self, node, ops):
        """Operands of a left-leaning chain a op b op c ..., with their operators.

        Returns ``[(None, a), (op, b), (op, c), ...]``; found iteratively so
        that a sum of 50 000 terms does not recurse 50 000 levels.
        """
        items = []
        while isinstance(node, ast.BinOp) and isinstance(node.op, ops):
            items.append((node.op, node.right))
            node = node.left
        items.append((None, node))
        items.reverse()
        return items

    def sum_chain(self, node, depth):
        terms = []
        for op, operand in self.chain(node, (ast.Add, ast.Sub)):
            value = self.build(operand, depth + 1)
            terms.append(-value if isinstance(op, ast.Sub) else value)
        self.check_number_size(node, terms)
        return sp.Add(*terms)

    def product_chain(self, node, depth):
        factors = []
        for op, operand in self.chain(node, (ast.Mult, ast.Div)):
            value = self.build(operand, depth + 1)
            if isinstance(op, ast.Div):
                if value == 0:
                    raise self.error(node, "division by zero")
                value = sp.Pow(value, -1)
            factors.append(value)
        self.check_number_size(node, factors)
        return sp.Mul(*factors)

    def power(self, node, depth):
        base = self.build(node.left, depth + 1)
        exponent = self.build(node.right, depth + 1)
        if exponent.is_Number:
            if abs(exponent) > _MAX_EXPONENT:
                raise self.error(node, f"numeric exponent {exponent} is too large "
                                       f"(at most {_MAX_EXPONENT} in absolute value)")
            coefficient = base.as_coeff_Mul()[0] if not base.is_Number else base
            if _bits(coefficient) * float(abs(exponent)) > _MAX_NUMBER_BITS:
                raise self.error(node, "numeric power too large to compute exactly")
            if base == 0 and exponent.is_negative:
                raise self.error(node, "division by zero")
            self.check_root(node, base, exponent)
        return self.real(node, sp.Pow(base, exponent))

    def check_root(self, node, base, exponent):
        """Refuse roots of huge exact numbers: sympy would try to factor them."""
        if isinstance(exponent, sp.Rational) and not exponent.is_Integer:
            coefficient = base if base.is_Number else base.as_coeff_Mul()[0]
            if isinstance(coefficient, sp.Rational) and \
                    max(int(coefficient.p).bit_length(), int(coefficient.q).bit_length()) > _MAX_ROOT_BITS:
                raise self.error(node, f"root of an exact number with more than "
                                       f"{_MAX_ROOT_BITS} bits (write it as a float)")

    def call(self, node, depth):
        func = node.func
        if not isinstance(func, ast.Name):
            raise self.error(node, "only calls of the functions "
                                   f"{', '.join(FUNCTIONS)} are allowed")
        ident = self.renamed.get(func.id, func.id)
        if ident not in FUNCTIONS:
            if ident in self.symbols or ident in CONSTANTS:
                raise self.error(node, f"{ident!r} is not a function")
            if ident.startswith("__"):
                raise self.error(node, f"name {ident!r} is not allowed")
            raise ParseError(f"{self.where}: unknown function {ident!r}"
                             f"{_suggest_from(ident, FUNCTIONS)} in {self.fragment(node)}")
        if node.keywords:
            raise self.error(node, "keyword arguments are not allowed")
        for arg in node.args:
            if isinstance(arg, ast.Starred):
                raise self.error(node, "starred arguments are not allowed")
        if len(node.args) != _ARITY[ident]:
            count = _ARITY[ident]
            raise self.error(node, f"{ident} takes {count} argument{'s' if count > 1 else ''}, "
                                   f"got {len(node.args)}")
        args = [self.build(arg, depth + 1) for arg in node.args]
        key = (ident, *args)
        if key not in self.calls:   # sympy evaluates sin(a - b) anew at every occurrence
            if ident == "sqrt":
                self.check_root(node, args[0], sp.S.Half)
            self.calls[key] = self.real(node, FUNCTIONS[ident](*args))
        return self.calls[key]

    def real(self, node, value):
        """``value``, refused when it is a constant that is not a real number."""
        if not value.free_symbols:
            complex_value = complex_string(value)
            if complex_value:
                raise ParseError(f"{self.where}: {self.fragment(node)} is not a real number "
                                 f"(its value is {complex_value}); nhham takes real data only")
        return value

    def check_number_size(self, node, items):
        """Refuse sums/products whose exact numbers could grow past the cap."""
        total = sum(_bits(item.as_coeff_Mul()[0]) for item in items)
        if total > _MAX_NUMBER_BITS:
            raise self.error(node, "exact numbers too large to compute")

    _HANDLERS = {
        ast.Constant: constant,
        ast.Name: name,
        ast.UnaryOp: unary,
        ast.BinOp: binop,
        ast.Call: call,
    }


def _bits(number) -> int:
    """Size in bits of an exact rational (0 for floats and non-numbers)."""
    if isinstance(number, sp.Rational):
        return int(number.p).bit_length() + int(number.q).bit_length()
    return 0


def _suggest_from(ident: str, names) -> str:
    close = difflib.get_close_matches(ident, list(names), n=1)
    return f"; did you mean {close[0]!r}?" if close else ""


def _quote(fragment: str) -> str:
    fragment = " ".join(fragment.split())
    if len(fragment) > _QUOTE_LIMIT:
        fragment = fragment[:_QUOTE_LIMIT - 3] + "..."
    return repr(fragment)


# Readable names for the constructs that are refused.
_NODE_NAMES = {
    ast.Attribute: "attribute access",
    ast.Subscript: "subscripting",
    ast.Lambda: "lambda",
    ast.ListComp: "a comprehension",
    ast.SetComp: "a comprehension",
    ast.DictComp: "a comprehension",
    ast.GeneratorExp: "a generator expression",
    ast.JoinedStr: "an f-string",
    ast.FormattedValue: "an f-string",
    ast.Compare: "comparison",
    ast.BoolOp: "a boolean operator",
    ast.IfExp: "a conditional expression",
    ast.NamedExpr: "assignment (:=)",
    ast.Starred: "starred expression",
    ast.Tuple: "a tuple",
    ast.List: "a list",
    ast.Set: "a set",
    ast.Dict: "a dict",
    ast.Await: "await",
    ast.Yield: "yield",
    ast.YieldFrom: "yield",
    ast.Slice: "slicing",
    ast.MatMult: "'@'",
    ast.Mod: "'%'",
    ast.FloorDiv: "'//'",
    ast.LShift: "'<<'",
    ast.RShift: "'>>'",
    ast.BitOr: "'|'",
    ast.BitXor: "'^' (use ** for powers)",
    ast.BitAnd: "'&'",
    ast.Invert: "'~'",
    ast.Not: "'not'",
}


def _describe(node) -> str:
    if isinstance(node, ast.Constant):
        kind = type(node.value).__name__
        return {"str": "a string", "bytes": "bytes", "complex": "a complex number",
                "bool": "a boolean", "NoneType": "None", "ellipsis": "'...'"}.get(
                    kind, f"a {kind} constant")
    return _NODE_NAMES.get(type(node), type(node).__name__)
