"""Strict, safe XML parsing of a URDF document with lxml.

No DTD is ever loaded, no entity is ever declared, resolved or expanded, nothing
is fetched from the network, and a malformed document is an error (never
"recovered" into a smaller one). Size, markup count, nesting depth and
attribute length are bounded by :class:`~kinengine.urdf.limits.Limits`.

Namespaces are read as urdfdom (TinyXML, which knows none) reads them: a prefix that
the root element does not declare (``<sensor:camera>`` in a ``<gazebo>`` block) is
declared on the root with a placeholder URI before parsing, so such an element parses
and is ignored like any non-URDF element; a default ``xmlns="..."`` is dropped from the
element names after parsing, so ``<robot xmlns="...">`` holds plain ``<link>`` and ``<joint>``.
"""

from __future__ import annotations

import codecs
import re

from lxml import etree

from ..errors import URDFError
from .limits import LIMITS, Limits

_PARSER_OPTIONS = {
    "resolve_entities": False,
    "no_network": True,
    "recover": False,
    "load_dtd": False,
    "dtd_validation": False,
    "attribute_defaults": False,
    "huge_tree": False,
    "remove_comments": True,
    "remove_pis": True,
}

# Encodings whose bytes hide ASCII markup (XML 1.0, appendix F); anything else is scanned as latin-1.
_WIDE_ENCODINGS = (
    (codecs.BOM_UTF32_LE, "utf-32"),
    (codecs.BOM_UTF32_BE, "utf-32"),
    (b"\x00\x00\x00<", "utf-32-be"),
    (b"<\x00\x00\x00", "utf-32-le"),
    (codecs.BOM_UTF16_LE, "utf-16"),
    (codecs.BOM_UTF16_BE, "utf-16"),
    (b"\x00<", "utf-16-be"),
    (b"<\x00", "utf-16-le"),
)
_DECLARED_ENCODING = re.compile(r"\A(\ufeff?<\?xml\s[^>]*?\bencoding\s*=\s*)(['\"])[^'\"]*\2")
_FIRST_START_TAG = re.compile(r"<[^!?]")
_DTD_MARKUP = re.compile(r"<!(DOCTYPE|ENTITY)\b")
# Patterns of the undeclared-prefix path (a malformed or namespaced document), compiled there on first use
# (re caches them) rather than by every import: ~0.4 ms.
_PROLOG = r"(?s)(?:\ufeff|\xef\xbb\xbf)?(?:\s|<\?.*?\?>|<!--.*?-->)*"
_ROOT_TAG = r"<([^\s/>]+)((?:\s+[^\s=/>]+\s*=\s*(?:\"[^\"]*\"|'[^']*'))*)\s*/?>"
_USED_PREFIX = r"(?a)</?([A-Za-z_][\w.-]*):[A-Za-z_]|\s([A-Za-z_][\w.-]*):[A-Za-z_][\w.-]*\s*="
_DECLARED_PREFIX = r"(?a)xmlns:([A-Za-z_][\w.-]*)\s*="
_PLACEHOLDER_URI = "urn:kinengine:undeclared-prefix:"
_UNDECLARED_PREFIX = r"Namespace prefix \S+ (for \S+ )?on \S+ is not defined"
_MAX_UNDECLARED = 256  # real files use a handful (sensor, gz, ...); each one adds an attribute to the root
_NO_DTD = (
    "is not allowed: kinengine reads no DTD and no entity declaration (they can read local "
    "files or expand without bound); remove it and write the values out"
)


def parse_xml(document: str | bytes, *, source: str = "<string>", limits: Limits = LIMITS) -> etree._Element:
    """The root element of ``document``, parsed strictly and safely; URDFError otherwise.

    ``str`` input is encoded as UTF-8 (an XML encoding declaration in it is
    rewritten to match); ``bytes`` follow their BOM or declaration.
    """
    data = _to_bytes(document, source, limits)
    _refuse_dtd(data, source)
    tags = data.count(b"<")
    if tags > limits.max_tags:
        raise URDFError(
            f"the document has {tags} markup tags, more than Limits.max_tags = {limits.max_tags}",
            source=source,
        )
    try:
        root = _parse(data)
    except etree.XMLSyntaxError as exc:
        declared = _declare_prefixes(data, source) if re.search(_UNDECLARED_PREFIX, exc.msg) else data
        if declared is data:
            raise URDFError(
                f"not well-formed XML: {exc.msg}", source=source, line=exc.lineno or None
            ) from None
        try:
            root = _parse(declared)
        except etree.XMLSyntaxError as again:
            raise URDFError(
                f"not well-formed XML: {again.msg}", source=source, line=again.lineno or None
            ) from None
    docinfo = root.getroottree().docinfo
    if docinfo.doctype or docinfo.internalDTD is not None or docinfo.externalDTD is not None:
        raise URDFError(f"a <!DOCTYPE> {_NO_DTD}", source=source)
    _check_shape(root, source, limits)
    for element in root.xpath("//*[namespace-uri() != '' and not(contains(name(), ':'))]"):
        element.tag = etree.QName(element).localname  # a default xmlns: <robot xmlns="..."> is <robot>
    return root


def _parse(data: bytes) -> etree._Element:
    parser = etree.XMLParser(**_PARSER_OPTIONS)  # one parser per call: lxml parsers are not thread-safe
    return etree.fromstring(data, parser)


def _declare_prefixes(data: bytes, source: str) -> bytes:
    """Called only when libxml2 met an undeclared prefix (a valid document pays nothing).

    ``data`` with each namespace prefix used in it but not declared on the root element declared there
    (xmlns:p="urn:kinengine:undeclared-prefix:p"); ``data`` itself if none is missing or the root start
    tag cannot be found. Only attributes are added to the root start tag, on its own line: no entity,
    DTD or markup is introduced and line numbers stay as they were."""
    codec = next((c for prefix, c in _WIDE_ENCODINGS if data.startswith(prefix)), "latin-1")
    if codec == "latin-1" and b":" not in data:
        return data
    try:
        text = data.decode(codec)
    except UnicodeDecodeError:
        return data  # lxml reports the bad encoding
    prolog = re.match(_PROLOG, text)
    assert prolog is not None  # every part of _PROLOG is optional: it matches at least the empty string
    root = re.compile(_ROOT_TAG).match(text, prolog.end())
    if root is None:
        return data
    used = {a or b for a, b in re.findall(_USED_PREFIX, text)} - {"xml", "xmlns"}
    missing = sorted(used - set(re.findall(_DECLARED_PREFIX, root.group(2))))
    if not missing:
        return data
    if len(missing) > _MAX_UNDECLARED:
        raise URDFError(
            f"the document uses {len(missing)} namespace prefixes that <{root.group(1)}> does not declare "
            f"(e.g. {missing[0]!r}), more than the {_MAX_UNDECLARED} kinengine declares for you; "
            'declare them with xmlns:prefix="..."',
            source=source,
        )
    declarations = "".join(f' xmlns:{p}="{_PLACEHOLDER_URI}{p}"' for p in missing)
    return (text[: root.end(1)] + declarations + text[root.end(1) :]).encode(codec)


def _to_bytes(document: object, source: str, limits: Limits) -> bytes:
    if isinstance(document, str):
        if len(document) > limits.max_bytes:  # every character takes at least one byte
            _too_big(len(document), source, limits)
        document = _DECLARED_ENCODING.sub(r"\1\2UTF-8\2", document, count=1)
        try:
            data = document.encode("utf-8")
        except UnicodeEncodeError as exc:
            raise URDFError(
                f"the text is not valid Unicode: {exc.reason} at character {exc.start}", source=source
            ) from None
    elif isinstance(document, (bytes, bytearray, memoryview)):
        data = bytes(document)
    else:
        raise URDFError(f"expected URDF text as str or bytes, got {type(document).__name__}", source=source)
    if len(data) > limits.max_bytes:
        _too_big(len(data), source, limits)
    return data


def _too_big(size: int, source: str, limits: Limits) -> None:
    raise URDFError(
        f"the document is {size} bytes, more than Limits.max_bytes = {limits.max_bytes}", source=source
    )


def _refuse_dtd(data: bytes, source: str) -> None:
    """URDFError if the prolog (the text before the root element) holds a DOCTYPE or ENTITY.

    Checked on the raw text, so that libxml2 never sees an entity declaration.
    """
    codec = next((c for prefix, c in _WIDE_ENCODINGS if data.startswith(prefix)), "latin-1")
    text = data.decode(codec, errors="replace")
    start = _FIRST_START_TAG.search(text)
    prolog = text[: start.start()] if start else text
    found = _DTD_MARKUP.search(prolog)
    if found:
        line = prolog.count("\n", 0, found.start()) + 1
        raise URDFError(f"<!{found.group(1)}> {_NO_DTD}", source=source, line=line)


def _check_shape(root: etree._Element, source: str, limits: Limits) -> None:
    """Nesting depth and attribute lengths, found by XPath in C (no Python recursion, any thread)."""
    too_deep = root.xpath("/*" * (limits.max_depth + 1))
    if too_deep:
        element = too_deep[0]
        raise URDFError(
            f"elements are nested deeper than Limits.max_depth = {limits.max_depth}",
            source=source,
            element=f"<{element.tag}>",
            line=element.sourceline,
        )
    too_long = root.xpath(f"//@*[string-length(.) > {int(limits.max_attribute_length)}]")
    if too_long:
        element = too_long[0].getparent()
        raise URDFError(
            f"attribute {too_long[0].attrname!r} has {len(too_long[0])} characters, more than "
            f"Limits.max_attribute_length = {limits.max_attribute_length}",
            source=source,
            element=f"<{element.tag}>",
            line=element.sourceline,
        )
