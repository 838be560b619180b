/* The metadata of a friction table file: a JSON object, scanned in place (no tree is built).
 *
 * table.py (tribocosim/components/stripdraw/table.py, the owner of the format) stores the metadata as
 * json.dumps(meta, sort_keys=True) (separators ", " and ": ", ensure_ascii) and hashes
 * json.dumps(meta without "content_hash", sort_keys=True, separators=(",", ":")). The two texts differ only
 * in the separators and the "content_hash" member, so the hashed text is derived from the stored one
 * LEXICALLY: whitespace outside strings is dropped and the top-level "content_hash" member left out. Numbers
 * are never re-serialised.
 *
 * That derivation equals Python's re-serialisation exactly when the stored text is in the form json.dumps
 * writes: keys sorted (by code point) and unique at every level, strings escaped as ensure_ascii escapes them
 * (\" \\ \b \f \n \r \t, \u00XX lowercase for the rest, no "\/"), integers as Python prints them (no "-0"),
 * floats as repr(float) prints them (shortest round-trip digits, 1e+16 / 1e-05 exponent rules, NaN, Infinity).
 * tc_json_hashed_text checks all of that and refuses, naming the first departure, any text it cannot derive
 * the hashed text of: a file written by write_table always passes.
 *
 * The text is ASCII bytes (the UTF-32 metadata narrowed by the caller; a byte >= 0x80 stands for any
 * non-ASCII character, which json.dumps with ensure_ascii never writes).
 */
#ifndef TC_JSON_H
#define TC_JSON_H

#include <stddef.h>

#include "tc_common.h"

/* nesting deeper than this is refused (Python's own limit is its recursion limit, about 1000) */
#define TC_JSON_MAX_DEPTH 128

enum tc_json_kind {
    TC_JSON_ABSENT = 0, /* tc_json_member: no such member */
    TC_JSON_NULL,
    TC_JSON_FALSE,
    TC_JSON_TRUE,
    TC_JSON_NUMBER, /* including NaN, Infinity, -Infinity (json.loads reads them) */
    TC_JSON_STRING,
    TC_JSON_ARRAY,
    TC_JSON_OBJECT
};

/* A value of the text: its kind and the span text[begin, end) of its token (strings with their quotes). */
typedef struct tc_json_value {
    int kind;
    size_t begin, end;
} tc_json_value;

/* TC_OK if text[0..n) is one JSON value as Python's json.loads reads it, and that value is an object;
 * TC_ERROR with a message otherwise. The functions below take texts that passed this check. */
TC_API int tc_json_check_object(const char *text, size_t n, tc_msg msg);

/* The value of the top-level member named key (the last one if the name repeats: json.loads keeps it);
 * kind TC_JSON_ABSENT if there is none. */
tc_json_value tc_json_member(const char *text, size_t n, const char *key);

/* 1 if v is a string whose decoded value is the ASCII text s. */
int tc_json_string_equals(const char *text, tc_json_value v, const char *s);

/* A string value decoded to UTF-8 in buf (NUL-terminated, cut at a character boundary to fit);
 * TC_ERROR if v is not a string. */
int tc_json_string(const char *text, tc_json_value v, char *buf, size_t size);

/* The value of a number (true and false count as 1 and 0, as in Python); 0 if v is not one of these.
 * Decimal conversion is correctly rounded and independent of the C locale. */
int tc_json_number(const char *text, tc_json_value v, double *x);

/* float(value) as Python computes it: a number, true/false, or a string holding a decimal number ("0.5",
 * " +.5e0 ", "inf"; not the rarer forms with underscores); 0 if Python's float() would fail. */
int tc_json_python_float(const char *text, tc_json_value v, double *x);

/* The value roughly as Python's repr prints it, for messages: None, True, 'text', 1.5, nan (cut to fit). */
void tc_json_repr(const char *text, tc_json_value v, char *buf, size_t size);

/* The text table.py hashes: text (checked) without whitespace outside strings and without the top-level
 * member drop_key, written to out (capacity: n bytes) with its length in *out_n. TC_ERROR, naming the first
 * departure and its offset, if the text is not in the form json.dumps(sort_keys=True) writes. */
TC_API int tc_json_hashed_text(const char *text, size_t n, const char *drop_key, char *out, size_t *out_n,
                               tc_msg msg);

#endif
