//! Labelled contact sheets of the sphere images: one row per image (reference, then each
//! sampler) with its label on the left, the materials named above their columns.

use plotters::prelude::*;

use crate::StudyError;

/// Width of the row-label margin (pixels).
const ROW_LABEL_PX: u32 = 260;
/// Height of the column-label band (pixels).
const COLUMN_LABEL_PX: u32 = 28;
/// Gap between rows (pixels).
const GAP_PX: u32 = 4;

/// A sheet of `rows` (`(label, image)`, images of equal height made of `columns.len()` equal
/// squares side by side), each row labelled on its left, each column (material) named above
/// its square. Errors only if the text cannot be drawn.
pub fn labelled_sheet(
    rows: &[(String, image::RgbImage)],
    columns: &[String],
) -> Result<image::RgbImage, StudyError> {
    crate::plot::register_font();
    let img_w = rows.iter().map(|r| r.1.width()).max().unwrap_or(1);
    let row_h = rows.iter().map(|r| r.1.height()).max().unwrap_or(1);
    let w = ROW_LABEL_PX + img_w;
    let h = COLUMN_LABEL_PX + rows.len() as u32 * (row_h + GAP_PX);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    let err = |x: &dyn std::fmt::Debug| StudyError::Plot {
        name: "sphere sheet".into(),
        reason: format!("{x:?}"),
    };
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        let font = ("sans-serif", 15).into_font().color(&BLACK);
        let n = columns.len().max(1) as u32;
        let col_w = img_w / n;
        for (k, c) in columns.iter().enumerate() {
            // Clip long names to the column's width (up to about 9 px per character at 15 px).
            let max_chars = (col_w / 9).max(4) as usize;
            let text: String = if c.chars().count() > max_chars {
                c.chars().take(max_chars - 1).chain(['…']).collect()
            } else {
                c.clone()
            };
            root.draw(&Text::new(
                text,
                ((ROW_LABEL_PX + k as u32 * col_w + 2) as i32, 6),
                font.clone(),
            ))
            .map_err(|x| err(&x))?;
        }
        for (i, (label, _)) in rows.iter().enumerate() {
            let y = COLUMN_LABEL_PX + i as u32 * (row_h + GAP_PX) + row_h / 2;
            root.draw(&Text::new(label.clone(), (6, y as i32 - 8), font.clone()))
                .map_err(|x| err(&x))?;
        }
        root.present().map_err(|x| err(&x))?;
    }
    let mut out =
        image::RgbImage::from_raw(w, h, buf).ok_or_else(|| err(&"buffer size".to_string()))?;
    for (i, (_, img)) in rows.iter().enumerate() {
        let y0 = COLUMN_LABEL_PX + i as u32 * (row_h + GAP_PX);
        for (x, y, p) in img.enumerate_pixels() {
            out.put_pixel(ROW_LABEL_PX + x, y0 + y, *p);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sheets_carry_row_and_column_labels() {
        let red = image::RgbImage::from_pixel(40, 20, image::Rgb([255, 0, 0]));
        let rows = vec![
            ("reference".to_string(), red.clone()),
            ("adaptive (64 spp)".to_string(), red),
        ];
        let sheet = labelled_sheet(&rows, &["ggx".into(), "rgl:paper_white_rgb".into()]).unwrap();
        assert_eq!(sheet.width(), ROW_LABEL_PX + 40);
        assert_eq!(sheet.height(), COLUMN_LABEL_PX + 2 * (20 + GAP_PX));
        // Text (dark pixels) in the label margin of each row and above the columns.
        let dark = |x0: u32, x1: u32, y0: u32, y1: u32| {
            (x0..x1).any(|x| (y0..y1).any(|y| sheet.get_pixel(x, y).0.iter().all(|c| *c < 128)))
        };
        assert!(dark(0, ROW_LABEL_PX, COLUMN_LABEL_PX, COLUMN_LABEL_PX + 20));
        assert!(dark(
            0,
            ROW_LABEL_PX,
            COLUMN_LABEL_PX + 24,
            COLUMN_LABEL_PX + 44
        ));
        assert!(dark(ROW_LABEL_PX, ROW_LABEL_PX + 40, 0, COLUMN_LABEL_PX));
        // The images are copied in.
        assert_eq!(
            sheet.get_pixel(ROW_LABEL_PX + 5, COLUMN_LABEL_PX + 5).0,
            [255, 0, 0]
        );
    }
}
