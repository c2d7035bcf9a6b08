// SPDX-License-Identifier: GPL-3.0-or-later
#include "tools/MoveDialog.h"

#include "view/CloudView.h"

#include <QDialogButtonBox>
#include <QDoubleSpinBox>
#include <QFormLayout>
#include <QLabel>
#include <QPushButton>
#include <QVBoxLayout>

namespace scandiff::gui {

MoveDialog::MoveDialog(CloudView& view, const std::vector<EntityId>& ids, QWidget* parent) : QDialog(parent), view_(view)
{
    setWindowTitle(tr("Move / rotate"));
    setObjectName("moveDialog");
    view_.startMovingEntities(ids);
    auto* layout = new QVBoxLayout(this);
    auto* help = new QLabel(tr("In the box around them: drag with the middle button (or Shift + left) to move, "
                               "with the left button on a face to turn about its centre; or type the motion. "
                               "Nothing changes until Apply."),
                            this);
    help->setWordWrap(true);
    layout->addWidget(help);
    const Eigen::Vector3d c = view_.movingCentre();
    layout->addWidget(new QLabel(tr("Turning about X %1, Y %2, Z %3").arg(c.x(), 0, 'f', 3).arg(c.y(), 0, 'f', 3).arg(c.z(), 0, 'f', 3), this));
    auto* form = new QFormLayout;
    const char* labels[6] = {QT_TR_NOOP("Move X (m)"), QT_TR_NOOP("Move Y (m)"), QT_TR_NOOP("Move Z (m)"),
                             QT_TR_NOOP("Heading, about Z (°)"), QT_TR_NOOP("Pitch, about Y (°)"), QT_TR_NOOP("Roll, about X (°)")};
    const char* names[6] = {"dx", "dy", "dz", "heading", "pitch", "roll"};
    for (int k = 0; k < 6; ++k) {
        auto* box = new QDoubleSpinBox(this);
        box->setObjectName(names[k]);
        box->setDecimals(4); // 0.1 mm, 0.0001°
        box->setRange(k < 3 ? -1e6 : (k == 4 ? -90.0 : -180.0), k < 3 ? 1e6 : (k == 4 ? 90.0 : 180.0));
        box->setSingleStep(k < 3 ? 0.01 : 1.0);
        box->setKeyboardTracking(false); // a typed number moves the cloud once, not at each digit
        connect(box, qOverload<double>(&QDoubleSpinBox::valueChanged), this, &MoveDialog::typed);
        form->addRow(tr(labels[k]), box);
        boxes_[static_cast<std::size_t>(k)] = box;
    }
    layout->addLayout(form);
    auto* buttons = new QDialogButtonBox(QDialogButtonBox::Apply | QDialogButtonBox::Reset | QDialogButtonBox::Cancel, this);
    buttons->button(QDialogButtonBox::Apply)->setObjectName("apply");
    connect(buttons->button(QDialogButtonBox::Apply), &QPushButton::clicked, this, [this] {
        emit applyRequested(matrix());
        accept();
    });
    connect(buttons->button(QDialogButtonBox::Reset), &QPushButton::clicked, this, [this] { setMotion(RigidMotion{}); });
    connect(buttons, &QDialogButtonBox::rejected, this, &QDialog::reject);
    layout->addWidget(buttons);
    connect(&view_, &CloudView::movedByChanged, this, &MoveDialog::dragged);
}

RigidMotion MoveDialog::motion() const
{
    RigidMotion m;
    m.offset = Eigen::Vector3d(boxes_[0]->value(), boxes_[1]->value(), boxes_[2]->value());
    m.heading = boxes_[3]->value();
    m.pitch = boxes_[4]->value();
    m.roll = boxes_[5]->value();
    return m;
}

void MoveDialog::setMotion(const RigidMotion& motion)
{
    updating_ = true;
    const double values[6] = {motion.offset.x(), motion.offset.y(), motion.offset.z(), motion.heading, motion.pitch, motion.roll};
    for (std::size_t k = 0; k < 6; ++k)
        boxes_[k]->setValue(values[k]);
    updating_ = false;
    typed();
}

Eigen::Matrix4d MoveDialog::matrix() const { return dragged_ ? *dragged_ : rigidMotionMatrix(motion(), view_.movingCentre()); }

void MoveDialog::typed()
{
    if (updating_)
        return;
    dragged_.reset();
    view_.setMovedBy(matrix());
}

void MoveDialog::dragged(const Eigen::Matrix4d& global)
{
    // The boxes show the drag rounded to their decimals; Apply applies the
    // drag itself, what the view shows, until something is typed.
    dragged_ = global;
    const RigidMotion m = rigidMotionOf(global, view_.movingCentre());
    updating_ = true;
    const double values[6] = {m.offset.x(), m.offset.y(), m.offset.z(), m.heading, m.pitch, m.roll};
    for (std::size_t k = 0; k < 6; ++k)
        boxes_[k]->setValue(values[k]);
    updating_ = false;
}

void MoveDialog::done(int result)
{
    view_.stopMovingEntities();
    QDialog::done(result);
}

} // namespace scandiff::gui
