/* The MatchPattern sample of the specification's Appendix B, for the MatchPattern benchmark only (it
   reads past an unclosed `[`, answers some lists wrongly and takes exponential time: see docs/guide/matchpattern.md).
   The text is the specification's, with the printing errors of the document corrected as the OPC
   Foundation's sample code has it (the range checks `if (p == 0 || p == ']') return FALSE;`).

   Included once per character type, with these macros defined:
     SAMPLE_TCHAR        the character type (TCHAR)
     SAMPLE_NAME         the function's name
     SAMPLE_ISTDIGIT(c)  _istdigit: isdigit for char, iswdigit for wide characters
     SAMPLE_BUDGET       (optional) a long counter decremented per call; at 0 the call gives up and
                         sets sample_cut (for inputs on which the sample would run for hours) */

#ifndef SAMPLE_CONVERT_CASE
#define SAMPLE_CONVERT_CASE
#include <ctype.h>
static inline int ConvertCase(int c, BOOL bCaseSensitive)
{
    return bCaseSensitive ? c : toupper(c);
}
static int sample_cut;
#endif

/* return TRUE if String Matches Pattern -- uses Visual Basic LIKE operator syntax.
   CAUTION: Function is recursive */
static BOOL SAMPLE_NAME(const SAMPLE_TCHAR *String, const SAMPLE_TCHAR *Pattern, BOOL bCaseSensitive)
{
    SAMPLE_TCHAR c, p, l;
#ifdef SAMPLE_BUDGET
    if (SAMPLE_BUDGET-- <= 0) {
        sample_cut = 1;
        return FALSE;
    }
#endif
    for (;;) {
        switch (p = (SAMPLE_TCHAR)ConvertCase(*Pattern++, bCaseSensitive)) {
        case 0: /* end of pattern */
            return *String ? FALSE : TRUE; /* if end of string TRUE */
        case '*':
            while (*String) { /* match zero or more char */
                if (SAMPLE_NAME(String++, Pattern, bCaseSensitive))
                    return TRUE;
#ifdef SAMPLE_BUDGET
                if (sample_cut)
                    return FALSE;
#endif
            }
            return SAMPLE_NAME(String, Pattern, bCaseSensitive);
        case '?':
            if (*String++ == 0) /* match any one char */
                return FALSE;   /* not end of string */
            break;
        case '[':
            /* match char set */
            if ((c = (SAMPLE_TCHAR)ConvertCase(*String++, bCaseSensitive)) == 0)
                return FALSE; /* syntax */
            l = 0;
            if (*Pattern == '!') { /* match a char if NOT in set [] */
                ++Pattern;
                while ((p = (SAMPLE_TCHAR)ConvertCase(*Pattern++, bCaseSensitive)) != '\0') {
                    if (p == ']') /* if end of char set, then */
                        break;    /* no match found */
                    if (p == '-') { /* check a range of chars? */
                        p = (SAMPLE_TCHAR)ConvertCase(*Pattern, bCaseSensitive); /* get high limit of range */
                        if (p == 0 || p == ']')
                            return FALSE; /* syntax */
                        if (c >= l && c <= p)
                            return FALSE; /* if in range, return FALSE */
                    }
                    l = p;
                    if (c == p)       /* if char matches this element */
                        return FALSE; /* return false */
                }
            } else { /* match if char is in set [] */
                while ((p = (SAMPLE_TCHAR)ConvertCase(*Pattern++, bCaseSensitive)) != '\0') {
                    if (p == ']')     /* if end of char set, then */
                        return FALSE; /* no match found */
                    if (p == '-') {   /* check a range of chars? */
                        p = (SAMPLE_TCHAR)ConvertCase(*Pattern, bCaseSensitive); /* get high limit of range */
                        if (p == 0 || p == ']')
                            return FALSE; /* syntax */
                        if (c >= l && c <= p)
                            break; /* if in range, move on */
                    }
                    l = p;
                    if (c == p) /* if char matches this element */
                        break;  /* move on */
                }
                while (p && p != ']') /* if char matches, then skip to end of set */
                    p = *Pattern++;
            }
            break;
        case '#':
            c = *String++;
            if (!SAMPLE_ISTDIGIT(c))
                return FALSE; /* not a digit */
            break;
        default:
            c = (SAMPLE_TCHAR)ConvertCase(*String++, bCaseSensitive);
            if (c != p)       /* check for exact char */
                return FALSE; /* not a match */
            break;
        }
    }
}
