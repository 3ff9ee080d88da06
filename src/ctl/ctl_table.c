/* SPDX-License-Identifier: LGPL-2.1-or-later */
#include <errno.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "ctl/ctl_table.h"

typedef struct cell {
        char *text;
        const char *color;
} cell;

struct ctl_table {
        size_t n_columns;
        char **names;
        bool *right;
        cell *cells;
        size_t n_cells;
};

int ctl_table_new(ctl_table **ret, size_t n_columns, const char *const *names) {
        ctl_table *t = calloc(1, sizeof(*t));
        if (!t)
                return -ENOMEM;
        t->n_columns = n_columns;
        t->names = calloc(n_columns, sizeof(char *));
        t->right = calloc(n_columns, sizeof(bool));
        if (!t->names || !t->right) {
                ctl_table_free(t);
                return -ENOMEM;
        }
        for (size_t i = 0; i < n_columns; i++) {
                t->right[i] = names[i][0] == '>';
                t->names[i] = strdup(names[i] + t->right[i]);
                if (!t->names[i]) {
                        ctl_table_free(t);
                        return -ENOMEM;
                }
        }
        *ret = t;
        return 0;
}

ctl_table *ctl_table_free(ctl_table *t) {
        if (!t)
                return NULL;
        for (size_t i = 0; i < t->n_columns && t->names; i++)
                free(t->names[i]);
        for (size_t i = 0; i < t->n_cells; i++)
                free(t->cells[i].text);
        free(t->names);
        free(t->right);
        free(t->cells);
        free(t);
        return NULL;
}

int ctl_table_add(ctl_table *t, const char *color, const char *fmt, ...) {
        va_list ap;
        char *s;

        va_start(ap, fmt);
        int n = vasprintf(&s, fmt, ap);
        va_end(ap);
        if (n < 0)
                return -ENOMEM;
        cell *v = realloc(t->cells, (t->n_cells + 1) * sizeof(*v));
        if (!v) {
                free(s);
                return -ENOMEM;
        }
        t->cells = v;
        t->cells[t->n_cells++] = (cell) { .text = s, .color = color };
        return 0;
}

size_t ctl_table_rows(const ctl_table *t) {
        return t->n_cells / t->n_columns;
}

static void print_cell(FILE *f, const char *text, const char *color, size_t width, bool right, bool last,
                       bool colors) {
        size_t len = strlen(text);
        size_t pad = width > len ? width - len : 0;

        if (right)
                fprintf(f, "%*s", (int) pad, "");
        if (colors && color)
                fprintf(f, "%s%s%s", color, text, CTL_ANSI_NORMAL);
        else
                fputs(text, f);
        if (!right && !last)
                fprintf(f, "%*s", (int) pad, "");
        if (!last)
                fputc(' ', f);
}

void ctl_table_print(const ctl_table *t, FILE *f, bool legend, bool colors) {
        size_t *width = calloc(t->n_columns, sizeof(size_t));
        size_t rows = ctl_table_rows(t);

        if (!width)
                return;
        for (size_t i = 0; i < t->n_columns; i++)
                width[i] = legend ? strlen(t->names[i]) : 0;
        for (size_t i = 0; i < rows * t->n_columns; i++) {
                size_t len = strlen(t->cells[i].text);
                if (len > width[i % t->n_columns])
                        width[i % t->n_columns] = len;
        }
        if (legend) {
                for (size_t i = 0; i < t->n_columns; i++)
                        print_cell(f, t->names[i], CTL_ANSI_HEADER, width[i], t->right[i],
                                   i + 1 == t->n_columns, colors);
                fputc('\n', f);
        }
        for (size_t row = 0; row < rows; row++) {
                for (size_t i = 0; i < t->n_columns; i++) {
                        const cell *c = &t->cells[row * t->n_columns + i];
                        print_cell(f, c->text, c->color, width[i], t->right[i], i + 1 == t->n_columns, colors);
                }
                fputc('\n', f);
        }
        free(width);
}
