/* Locale-independent numbers for text formats: see text_number.h. */
#include "text_number.h"

#include <locale.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

char text_locale_point(void)
{
    const struct lconv *lc = localeconv();
    return (lc && lc->decimal_point && lc->decimal_point[0]) ? lc->decimal_point[0] : '.';
}

static double strtod_with_point(const char *s, char **end, char point)
{
    if (point == '.') return strtod(s, end);
    /* Copy the number (whitespace, then the characters a number can hold) with '.' swapped for
     * the locale's point; the swap keeps every offset, so end maps back one to one. */
    char copy[96];
    size_t n = 0;
    while (n + 1 < sizeof copy && (s[n] == ' ' || s[n] == '\t' || s[n] == '\n' || s[n] == '\r' ||
                                    s[n] == '\f' || s[n] == '\v'))
        copy[n] = s[n], ++n;
    while (n + 1 < sizeof copy && s[n] != '\0' && strchr("0123456789+-.eExXabcdfABCDFinftyINFTY", s[n])) {
        copy[n] = s[n] == '.' ? point : s[n];
        ++n;
    }
    copy[n] = '\0';
    char *copy_end = NULL;
    double v = strtod(copy, &copy_end);
    if (end) *end = (char *)s + (copy_end - copy);
    return v;
}

double text_strtod(const char *s, char **end)
{
    return strtod_with_point(s, end, text_locale_point());
}

void text_use_dot(char *text, char point)
{
    if (point == '.') return;
    for (char *p = text; *p; ++p)
        if (*p == point) *p = '.';
}

int text_format_double(char *buf, size_t cap, const char *fmt, double value)
{
    int n = snprintf(buf, cap, fmt, value);
    if (cap > 0) text_use_dot(buf, text_locale_point());
    return n;
}
